"""Typed errors; every message names the bad value and what was expected."""
from collections.abc import Iterable
import os

__all__ = ["QuadcogError", "GeneratedFilesError", "InputError", "ParameterError", "CompileError",
           "QuadcogWarning", "EulerSingularityError", "TargetError", "ExportError",
           "ScenarioError", "OverrideError", "ReferenceWarning", "KernelError", "SweepError",
           "PhysicalConsistencyError", "MissingDependencyError", "LogError", "LogFormatError",
           "LogCRCError", "LogSignalError", "IdentificationError", "StackError",
           "FirmwareError", "FirmwareBuildError"]
__all__ += ["Px4Error", "Px4TimeoutError"]
__all__ += ["VehicleFileError"]


class QuadcogError(Exception):
    """Base class of every quadcog error."""


class GeneratedFilesError(QuadcogError):
    """A file of generated/ is missing, corrupted or stale; the fix is `make derive`."""


class InputError(QuadcogError, ValueError):
    """An argument has the wrong shape, a non-finite value or is out of range."""


class ParameterError(InputError):
    """A parameter set is not admissible (m, g or inertia not positive, I_G not definite, ...)."""


class CompileError(QuadcogError):
    """The C compiler failed on generated code."""


class QuadcogWarning(UserWarning):
    """Warnings such as falling back to CasADi's virtual machine without a C compiler."""


class EulerSingularityError(QuadcogError):
    """|theta| reached pi/2, where the ZYX Euler-angle kinematics are singular."""


class TargetError(QuadcogError):
    """The cross toolchain or QEMU is missing or a target run failed."""


class ExportError(QuadcogError):
    """A controller cannot be exported: the message names the controller and the reason."""


class StackError(QuadcogError):
    """A third-party tree (a flight stack, a peer suite, a firmware) is missing or is not one,
    or its build failed; the message says what is missing and how to get it
    (quadcog.codegen.third_party, quadcog.stacks). Its subclass FirmwareError is the
    Crazyflie firmware builds' of the embedded export."""


class FirmwareError(StackError):
    """A Crazyflie firmware tree that ``quadcog export --target crazyflie`` builds in is
    missing or is not one: the message names the folder, where it came from (argument,
    environment variable) and the files that are missing. A StackError: the same tree finder
    (quadcog.codegen.third_party) as the firmware in the loop's."""


class FirmwareBuildError(FirmwareError, CompileError):
    """A firmware build failed: the message gives the compiler's first error line and the log.
    Both a FirmwareError (the firmware's build) and a CompileError (a compiler's failure)."""


class ScenarioError(InputError):
    """A scenario file is malformed: the message names the file, the key and what was expected."""


class OverrideError(InputError):
    """A ``--set`` argument is malformed (no ``=``, empty key, a path through a non-table)."""


class ReferenceWarning(QuadcogWarning):
    """A reference asks for more acceleration or jerk than the vehicle can give."""


class KernelError(QuadcogError):
    """The vector kernel cannot be built here (no compiler, no libmvec, an operation without
    a C form in quadcog.codegen.sx_to_c, an instruction set this CPU does not have)."""


class SweepError(InputError):
    """A sweep file is malformed: the message names the file, the key and what was expected."""


class PhysicalConsistencyError(ParameterError):
    """Ten inertial parameters pi that no rigid body has: the pseudo-inertia matrix is not
    positive definite (m <= 0, or the principal inertias about the CoG are not positive or
    break the triangle inequality; docs/model.md sec. 7.2)."""


class MissingDependencyError(QuadcogError, ImportError):
    """An optional package is not installed; the message gives the install command."""


class PeerStateError(InputError):
    """A peer simulator's state dictionary lacks what a quadcog law needs, or holds a value of
    the wrong shape; the message names the key (quadcog.aqb)."""


__all__ += ["PeerStateError"]


class LogError(InputError):
    """A flight log cannot be read or written (quadcog.logs); the message names the file."""


class LogFormatError(LogError):
    """A flight log's content is damaged or unsupported: wrong magic, truncated, unknown type,
    a non-numeric or NaN cell, time not strictly increasing."""


class LogCRCError(LogFormatError):
    """A Crazyflie uSD log whose CRC-32 does not match.

    ``path``, ``expected`` (stored in the file) and ``found`` (computed) are attributes.

    Parameters
    ----------
    path : str or os.PathLike
        The log file.
    expected : int
        The CRC-32 the file stores.
    found : int
        The CRC-32 its content gives.
    """

    def __init__(self, path: str | os.PathLike[str], expected: int, found: int) -> None:
        self.path, self.expected, self.found = str(path), int(expected), int(found)
        super().__init__(f"{self.path}: CRC-32 mismatch: the file stores 0x{self.expected:08x}, "
                         f"its content gives 0x{self.found:08x} (damaged or truncated file)")


class LogSignalError(LogError):
    """A flight log lacks a signal that was asked for.

    ``signal``, ``source`` and ``available`` (the signals it has) are attributes.

    Parameters
    ----------
    message : str
        The message, naming the log and the signal.
    signal : str, optional
        The signal asked for.
    source : str, optional
        The log (its path or name).
    available : iterable of str, optional
        The signals the log has.
    """

    def __init__(self, message: str, signal: str | None = None, source: str | None = None,
                 available: Iterable[str] = ()) -> None:
        self.signal, self.source, self.available = signal, source, tuple(available)
        super().__init__(message)


class IdentificationError(InputError):
    """A CoG/mass identification cannot run on the logs given (quadcog.identification): a
    missing signal, too few hover samples, no rotor model; the message names the log."""


class VehicleFileError(InputError):
    """A vehicle description file (URDF, SDF) lacks a value the vehicle needs, or holds one
    that is not a number: the message names the file and the value (its element path)."""


class SweepLockedError(SweepError):
    """Another live sweep is writing into the same results folder (its lock file
    ``.sweep.lock`` names the pid)."""


class SizeError(InputError):
    """A size or count (flights, samples, grid points, workers, rows) too large to allocate
    or to finish: refused before any work, naming the size and the limit."""


class SchedulerError(QuadcogError):
    """A Dask scheduler address of the wrong form, or a scheduler that does not answer within
    the stated time."""


class Px4Error(QuadcogError):
    """PX4 in the loop (quadcog.px4) failed: no PX4 tree where it was looked for, a tree that
    does not build (the compiler's first error line), no free instance (ports taken), PX4 died
    or refused the mission; the message names the tree, the port or the log."""


class Px4TimeoutError(Px4Error, TimeoutError):
    """PX4 did not connect to the simulator port, or stopped answering the lockstep (no
    HIL_ACTUATOR_CONTROLS), within the stated wall-clock time."""


class Interrupted(KeyboardInterrupt):
    """SIGINT or SIGTERM arrived; ``signum`` is the signal and ``status`` the exit status a
    shell reports for it (128 + signum: 130, 143). A KeyboardInterrupt, not a QuadcogError,
    so that no ``except Exception`` (nor ``except QuadcogError``) swallows it and every
    ``finally`` clean-up runs on the way out."""

    def __init__(self, signum):
        import signal
        self.signum = int(signum)
        self.status = 128 + self.signum
        super().__init__(f"interrupted by {signal.Signals(self.signum).name}")


class AttitudeError(InputError):
    """An attitude that is not one: a matrix that is not a rotation (R^T R != I or det R != 1)
    or a quaternion whose norm is not 1 (a zero quaternion has no attitude)."""


__all__ += ["AttitudeError"]
