"""Flight logs in: a real vehicle's log turned into time-aligned standard signals in SI units
and quadcog's frames (body x forward, y left, z up; ground frame z up), whatever the source.

``read_log(path)`` reads a Crazyflie uSD-deck binary log (``"crazyflie-usd"``, CRC-32
checked), a PX4 ULog (``"ulog"``, through pyulog), or a table with named columns (``"csv"``,
``"parquet"``); ``write_log(log, path, format)`` writes each of them. ``SIGNALS`` is the table
of standard signals (name -> shape of a sample, unit, meaning, components); ``FlightLog``
holds one flight. Conversions, frames and time bases: docs/logs.md and each reader's module
(quadcog.logs.crazyflie, quadcog.logs.ulog, quadcog.logs.table).
"""
from quadcog.logs.flightlog import FlightLog
from quadcog.logs.io import detect_format, read_log, write_log
from quadcog.logs.signals import LOG_FORMATS, SIGNALS, SignalSpec, signal_columns, table_columns

__all__ = ["FlightLog", "LOG_FORMATS", "SIGNALS", "SignalSpec", "detect_format", "read_log",
           "signal_columns", "table_columns", "write_log"]
