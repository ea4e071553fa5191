"""File input and output shared by the library and the command line: one place that reads and writes.

* :func:`read_text` -- a text file (parameter file, URDF) read as UTF-8; an unreadable, empty-named,
  directory or non-UTF-8 path is a typed error naming the file and the problem, never a raw
  ``OSError`` or ``UnicodeDecodeError``.
* :func:`atomic_write` / :func:`atomic_path` -- every file alpes_dyn writes (URDFs, figures, compiled
  libraries) is first written to a temporary file in the destination's directory, flushed to disk
  (``fsync``) and then renamed over the destination (atomic on POSIX): a full disk, a killed process
  or any error leaves either the old file or none, never a truncated one, and the temporary file is
  removed on failure.
* :func:`check_output_path` -- an output path is validated before any work is done (not empty, not
  a directory, an existing parent directory, a known extension).
* :func:`native_stderr_to` -- text that C++ libraries print on the process's standard error (file
  descriptor 2, e.g. urdfdom's parse errors) is captured so that it can go into one error line.
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from pathlib import Path
from typing import Iterator, Sequence

from .errors import AlpesDynError, InputError

__all__ = ["read_text", "atomic_write", "atomic_path", "check_output_path", "native_stderr_to"]


def _path(path: str | os.PathLike[str], what: str, error: type[AlpesDynError]) -> Path:
    if not isinstance(path, (str, os.PathLike)):
        raise error(f"{what}: expected a file path, got {type(path).__name__}")
    text = os.fspath(path)
    if isinstance(text, bytes) or not str(text).strip():
        raise error(f"{what}: empty file name")
    return Path(text)


def read_text(path: str | os.PathLike[str], what: str, error: type[AlpesDynError] = InputError) -> str:
    """The content of a UTF-8 text file.

    Parameters
    ----------
    path: the file.
    what: how the error names it, e.g. ``"parameter file"``.
    error: the :class:`~alpes_dyn.errors.AlpesDynError` subclass raised (default InputError).

    Raises
    ------
    ``error`` with one line: empty name, missing, a directory, unreadable, or not UTF-8 text (with
    the offset of the first bad byte).
    """
    p = _path(path, what, error)
    try:
        data = p.read_bytes()
    except IsADirectoryError:
        raise error(f"{what} {str(p)!r}: is a directory, expected a file") from None
    except OSError as exc:
        raise error(f"{what} {str(p)!r}: cannot be read ({exc.strerror or exc})") from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"{what} {str(p)!r}: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start})") from None


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], what: str = "output") -> Iterator[Path]:
    """Context manager yielding a temporary path next to ``path``; renamed over ``path`` on success.

    The temporary file keeps ``path``'s extension (for writers that choose the format by it, e.g.
    matplotlib) and is flushed to disk before the rename; on any exception it is removed and the
    destination is left as it was. ``OSError`` becomes :class:`~alpes_dyn.errors.InputError` naming
    ``what`` and the path.
    """
    dest = _path(path, what, InputError)
    if dest.is_dir():
        raise InputError(f"{what}: {str(dest)!r} is a directory, expected a file name")
    parent = dest.parent
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{dest.name}.", suffix=f".tmp{dest.suffix}", dir=parent)
    except OSError as exc:
        raise InputError(f"{what}: cannot write {str(dest)!r} ({exc.strerror or exc})") from None
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        with open(tmp_path, "rb+") as f:  # the writer may have closed the file: flush it to disk here
            os.fsync(f.fileno())
        os.chmod(tmp_path, 0o666 & ~_UMASK)  # mkstemp makes 0o600; a written file gets the usual mode
        os.replace(tmp_path, dest)
    except OSError as exc:
        _unlink(tmp_path)
        raise InputError(f"{what}: cannot write {str(dest)!r} ({exc.strerror or exc})") from None
    except BaseException:
        _unlink(tmp_path)
        raise
    _fsync_dir(parent)


def atomic_write(path: str | os.PathLike[str], data: str | bytes, what: str = "output") -> Path:
    """Write ``data`` (str as UTF-8, or bytes) to ``path`` atomically (see :func:`atomic_path`)."""
    payload = data.encode("utf-8") if isinstance(data, str) else bytes(data)
    with atomic_path(path, what) as tmp:
        with open(tmp, "wb") as f:
            f.write(payload)
            f.flush()
            os.fsync(f.fileno())
    return Path(path)


def check_output_path(path: str | None, what: str, extensions: Sequence[str] | None = None) -> Path:
    """Validate an output file name before any work: not empty, not a directory, its directory exists
    and is writable, and (if given) its extension is one of ``extensions`` (lower-case, without dot)."""
    p = _path(path if path is not None else "", what, InputError)
    if p.is_dir():
        raise InputError(f"{what}: {str(p)!r} is a directory, expected a file name")
    if extensions is not None:
        ext = p.suffix.lower().lstrip(".")
        if ext not in extensions:
            raise InputError(f"{what}: {str(p)!r} has {'extension ' + repr(ext) if ext else 'no extension'}; "
                             f"expected one of {', '.join('.' + e for e in extensions)}")
    parent = p.parent if str(p.parent) else Path(".")
    if parent.exists() and not parent.is_dir():
        raise InputError(f"{what}: {str(parent)!r} in {str(p)!r} is not a directory")
    if not parent.is_dir():
        raise InputError(f"{what}: directory {str(parent)!r} of {str(p)!r} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"{what}: directory {str(parent)!r} is not writable")
    return p


@contextlib.contextmanager
def native_stderr_to(sink: list[str]) -> Iterator[None]:
    """Capture what native code writes to file descriptor 2 inside the block; its lines are appended
    to ``sink`` (Python's ``sys.stderr`` is flushed first and is captured as well)."""
    fd = 2  # the process's standard error, whatever sys.stderr is
    try:
        sys.stderr.flush()
    except (OSError, ValueError):
        pass
    with tempfile.TemporaryFile() as tmp:
        saved = os.dup(fd)
        try:
            os.dup2(tmp.fileno(), fd)
            yield
        finally:
            try:
                sys.stderr.flush()
            except (OSError, ValueError):
                pass
            os.dup2(saved, fd)
            os.close(saved)
            tmp.seek(0)
            sink.extend(line.strip() for line in tmp.read().decode("utf-8", "replace").splitlines() if line.strip())


def _unlink(p: Path) -> None:
    try:
        p.unlink()
    except OSError:
        pass


def _read_umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


_UMASK = _read_umask()  # once, at import (os.umask is process-wide)


def _fsync_dir(d: Path) -> None:
    """Make a rename durable (best effort: not every file system supports fsync on a directory)."""
    try:
        fd = os.open(d, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
