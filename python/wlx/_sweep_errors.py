"""How the sweep says what went wrong: its error types, the input quoted in messages (bounded
excerpts, no control characters), a "did you mean" for a misspelt name, and stderr that never stops
a sweep. Every other module of the sweep reports through these."""

import reprlib
import sys


# Text from the input in an error message: at most this many characters of it.
MAX_EXCERPT = 60


class SweepError(ValueError):
    """A mistake in a sweep's spec or arguments: the message names the field and the reason."""


def _error(field, reason):
    # wlx.Error when the package is there (a ValueError either way), so callers catch one type.
    try:
        from . import Error
    except ImportError:  # pragma: no cover - only without the compiled module
        raise SweepError(f"{field}: {reason}") from None
    raise Error(f"{field}: {reason}") from None


_REPR = reprlib.Repr()  # bounded work on any value: a deep or shared structure is not written out whole
_REPR.maxlevel, _REPR.maxstring, _REPR.maxother = 3, MAX_EXCERPT, MAX_EXCERPT


def _excerpt(value):
    try:
        text = _REPR.repr(value)
    except Exception:  # noqa: BLE001 - a value without a repr (an int of more than 4300 digits)
        text = f"a {type(value).__name__}"
    return text if len(text) <= MAX_EXCERPT else text[:MAX_EXCERPT - 3] + "..."


def _key(name):
    """A key or name from the input as it goes into an error's field: as given when it is a short
    printable name, else its excerpt (quoted, escaped and cut: no control characters reach the
    terminal, no megabyte of key the message)."""
    return name if isinstance(name, str) and 0 < len(name) <= MAX_EXCERPT and name.isprintable() else _excerpt(name)


def _nearest(name, names):
    import difflib

    if not isinstance(name, str) or len(name) > 200:  # no "did you mean" for a value that is not a short name
        return ""
    close = difflib.get_close_matches(name, list(names), n=1, cutoff=0.6)
    return f"; did you mean {close[0]!r}?" if close else ""


def _one_line(text, limit=500):
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[:limit - 3] + "..."


class OutputError(OSError):
    """An output that could not be written (full disk, no permission): exit 74 on the command line."""


def _say(text):
    try:
        sys.stderr.write(text)
        sys.stderr.flush()
    except (OSError, AttributeError, ValueError):  # a closed stderr never stops a sweep
        pass
