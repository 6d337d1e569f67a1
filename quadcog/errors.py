"""Typed errors; every message names the bad value and what was expected."""


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


class IdentificationError(InputError):
    """A CoG/mass identification cannot run on the logs given (quadcog.identification): a
    missing signal, too few hover samples, no rotor model; the message names the log."""
