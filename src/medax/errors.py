"""One exception hierarchy for everything medax refuses or fails at.

Every message says what was found, where (which side, corner, face or file) and, where it
helps, what to do instead. The CLI prints ``str(err)`` on one line and exits non-zero.
"""


class MedaxError(Exception):
    """Root of all medax errors."""


class InputError(MedaxError, ValueError):
    """A user input (file, argument, option) is missing or malformed."""


class RegionError(InputError):
    """A 4-sided region is not valid (open corner, zero-length or crossing sides)."""


class CurveError(InputError):
    """A side curve definition is not valid (unknown kind, bad parameters)."""


class TraceError(MedaxError, RuntimeError):
    """The medial-axis tracer could not follow the axis from B1 to B2."""


class MeshError(MedaxError, RuntimeError):
    """A structured mesh could not be built on a region."""


class CadError(MedaxError, RuntimeError):
    """A CAD file could not be read, classified or rebuilt."""


class OutputError(MedaxError, RuntimeError):
    """An output could not be written (nothing was written, any previous file is intact)."""
