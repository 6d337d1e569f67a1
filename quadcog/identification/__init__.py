"""Identify a real vehicle's CoG offset and mass from its flight logs (``quadcog identify``).

``identify(logs, vehicle, baseline=None, method="auto")`` returns an ``Identification``: the
static balance at hover or the whole-flight least squares with the generated regressor
(``quadcog.identification.estimators``), pooled over the logs and, with a baseline, relative
to flights without the payload (``quadcog.identification.core``). The method: docs/identify.md.
"""
from quadcog.identification.core import IDENTIFIABLE_FRACTION, JSON_KEYS, METHODS, R_G_NAMES, Identification, identify
from quadcog.identification.identified import identified_cog

__all__ = ["IDENTIFIABLE_FRACTION", "JSON_KEYS", "METHODS", "R_G_NAMES", "Identification",
           "identified_cog", "identify"]
