"""Errors of the Python API: one class per kind of failure, each a subclass of both
tunetrace.Error and the built-in exception Python code catches for it (FileNotFoundError,
ValueError, KeyError, TypeError, MemoryError, ...). The status codes come from the library by
name (tt_status_name), never copied as numbers.

Internal: the public names are re-exported by tunetrace/__init__.py."""
import errno
import os

from ._lib import lib, text


def _status_codes():
    """{"TT_ERR_NO_DATA": -8, ...}: every code the library names."""
    return {text(lib.tt_status_name(c)): c for c in range(-64, 65) if lib.tt_status_name(c)}


STATUS = _status_codes()
"""The library's status codes by identifier ({"TT_OK": 0, "TT_ERR_IO": -3, ...})."""


class Error(Exception):
    """A libtunetrace call failed. str(e) is the library's message (it names the file, the
    field and what was expected); e.status is the tt_status code (negative), e.status_name
    its name ("parse error", "I/O error", ...). Every error the package raises is an Error,
    and also the built-in exception for its kind (see the subclasses)."""

    def __init__(self, status, message):
        super().__init__(message)
        self.status = status
        self.status_name = text(lib.tt_status_string(status))

    def __str__(self):  # KeyError and OSError would otherwise quote or reformat the message
        return str(self.args[0]) if self.args else ""


class InvalidArgumentError(Error, ValueError):
    """A value the library or the package refuses (TT_ERR_INVALID_ARGUMENT): a parameter out
    of its range, an AOV name that does not exist, a path with a NUL character."""


class ParseError(Error, ValueError):
    """Malformed input: a scene, JSON, image or weight file (TT_ERR_PARSE)."""


class InfeasibleError(Error, ValueError):
    """A configuration violates a constraint of the plugin's space (TT_ERR_INFEASIBLE)."""


class NumericError(Error, ArithmeticError):
    """NaN, infinity or another numerical failure (TT_ERR_NUMERIC)."""


class UnknownNameError(Error, KeyError):
    """A plugin, parameter or option name the session does not know (set("plugin.typo", v),
    config("not_loaded")); the message suggests the nearest name."""


class FileError(Error, OSError):
    """A file could not be read or written (TT_ERR_IO); e.filename names it when known."""


class NotFoundError(FileError, FileNotFoundError):
    """A file (scene, image, database, plugin) that does not exist; e.errno is ENOENT."""


class OutOfMemoryError(Error, MemoryError):
    """The library ran out of memory (TT_ERR_OUT_OF_MEMORY)."""


class ArgumentTypeError(Error, TypeError):
    """An argument of the wrong type (render(spp="4")); raised by the package before any
    library call."""


class PluginError(Error, ImportError):
    """A plugin file that cannot be used: ABI mismatch, missing functions, init failed
    (TT_ERR_ABI)."""


class UnsupportedError(Error, NotImplementedError):
    """A feature this build or plugin does not provide (TT_ERR_UNSUPPORTED)."""


class NoDataError(Error, LookupError):
    """Nothing to answer from: a metric the integrator does not publish, a predictor that
    observed nothing (TT_ERR_NO_DATA)."""


class StopRequested(Error):
    """The user asked to stop (TT_ERR_INTERRUPTED)."""


class InternalError(Error, RuntimeError):
    """A bug in the library or a plugin (TT_ERR_INTERNAL): please report it."""


_BY_STATUS = {
    "TT_ERR_INVALID_ARGUMENT": InvalidArgumentError, "TT_ERR_OUT_OF_MEMORY": OutOfMemoryError,
    "TT_ERR_IO": FileError, "TT_ERR_PARSE": ParseError, "TT_ERR_UNSUPPORTED": UnsupportedError,
    "TT_ERR_INFEASIBLE": InfeasibleError, "TT_ERR_ABI": PluginError,
    "TT_ERR_NO_DATA": NoDataError, "TT_ERR_INTERRUPTED": StopRequested,
    "TT_ERR_INTERNAL": InternalError, "TT_ERR_NUMERIC": NumericError,
}
_CLASS_OF = {STATUS[name]: cls for name, cls in _BY_STATUS.items() if name in STATUS}

# what the library's messages say of a file that does not exist (strerror(ENOENT), OIIO's
# "Could not open file", the plugin resolver's "not found")
_MISSING = (os.strerror(errno.ENOENT), "not found", "Could not open file")


def make_error(status, message, filename=None, cls=None):
    """The exception for a failed call: the class of `status` (a missing file's I/O error:
    NotFoundError), or `cls` when given; `filename` is the path the call was given."""
    if cls is None:
        cls = _CLASS_OF.get(status, Error)
        if cls is FileError and (any(m in message for m in _MISSING) or
                                 (filename is not None and not os.path.lexists(filename))):
            cls = NotFoundError
    e = cls(status, message)
    if isinstance(e, OSError):
        e.errno = errno.ENOENT if isinstance(e, FileNotFoundError) else None
        e.filename = os.fsdecode(filename) if filename is not None else None
    return e


def last_error_text(status):
    """The calling thread's last library message, or the status's name when there is none."""
    raw = lib.tt_last_error()
    msg = raw.decode(errors="replace") if raw else ""
    return msg or text(lib.tt_status_string(status))


def check(status, what=None, filename=None, cls=None):
    """Raises the error of a negative status with the library's message (prefixed by
    `what`); returns the status otherwise."""
    if status < 0:
        msg = last_error_text(status)
        raise make_error(status, f"{what}: {msg}" if what else msg, filename, cls)
    return status
