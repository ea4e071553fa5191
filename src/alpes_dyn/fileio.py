"""File input and output shared by the library and the command line: one place that reads and writes.

* :func:`read_bytes` / :func:`read_text` -- an input file (parameter file, spec, URDF, recording) is
  opened without blocking (``O_NONBLOCK``: a FIFO with no writer is refused, never waited on), must
  be a regular file (not a directory, device or FIFO) of at most a documented size
  (:data:`alpes_dyn.limits.MAX_TEXT_BYTES`, :data:`~alpes_dyn.limits.MAX_RECORDING_BYTES`), checked
  before it is read; text is UTF-8, a leading byte-order mark is accepted. Every failure is a typed
  error naming the file and the problem, never a raw ``OSError`` or ``UnicodeDecodeError``.
* :func:`check_outputs` -- **the output policy** of every command that writes, applied before any
  work: an output must not be one of the run's inputs (the same file, by inode, whatever its name)
  nor another output of the run, nor an existing directory, device, FIFO or other non-regular file,
  nor a symbolic link (refused, not followed: replacing it would replace the link), nor a name
  ending in ``/``; its directory must exist and be writable. :func:`check_output_path` is the check
  of one output.
* :func:`atomic_write` / :func:`atomic_path` -- every file alpes_dyn writes (URDFs, recordings,
  parameter files, figures, compiled libraries) is first written to a temporary file
  ``.NAME.XXXX.tmp.EXT`` in the destination's directory, flushed to disk (``fsync``) and then renamed
  over the destination (atomic on POSIX): a full disk, a killed process or any error leaves either
  the old file or none, never a truncated one. The temporary file is removed on any exception and on
  SIGINT, SIGTERM and SIGHUP (:func:`signals_as_exceptions`); only SIGKILL can leave it behind.
* :func:`native_stderr_to` -- text that C++ libraries print on the process's standard error (file
  descriptor 2, e.g. urdfdom's parse errors) is captured so that it can go into one error line.
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import signal
import stat
import sys
import tempfile
import threading
from pathlib import Path
from typing import Iterator, Sequence

from .errors import AlpesDynError, InputError
from .limits import MAX_TEXT_BYTES

__all__ = ["read_bytes", "read_text", "decode_utf8", "load_toml", "atomic_write", "atomic_path", "check_output_path", "check_outputs",
           "writable_directory",
           "signals_as_exceptions", "native_stderr_to", "check_output_directory", "write_directory"]

def _path(path: str | os.PathLike[str], what: str, error: type[AlpesDynError]) -> Path:
    if not isinstance(path, (str, os.PathLike)):
        raise error(f"{what}: expected a file path, got {type(path).__name__}")
    text = os.fspath(path)
    if isinstance(text, bytes) or not str(text).strip():
        raise error(f"{what}: empty file name")
    if "\0" in text:
        raise error(f"{what}: the file name {text[:80]!r} contains a NUL byte")
    return Path(text)


def _kind(mode: int) -> str:
    """What a non-regular file is, for a message."""
    for test, name in ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket"), (stat.S_ISLNK, "a symbolic link")):
        if test(mode):
            return name
    return "not a regular file"


def read_bytes(path: str | os.PathLike[str], what: str, error: type[AlpesDynError] = InputError,
               limit: int = MAX_TEXT_BYTES) -> bytes:
    """The content of a regular file of at most ``limit`` bytes.

    The file is opened with ``O_NONBLOCK`` (a FIFO without a writer does not block) and checked with
    ``fstat`` before anything is read: a directory, FIFO, device or socket, or a file over ``limit``
    bytes, is ``error`` with one line naming ``what`` and the path.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str
        How the error names the file, e.g. ``"parameter file"``.
    error : type, optional
        The :class:`~alpes_dyn.errors.AlpesDynError` subclass raised (default InputError).
    limit : int, optional
        The largest accepted size, bytes (default :data:`alpes_dyn.limits.MAX_TEXT_BYTES`).

    Returns
    -------
    bytes
        The file's content.

    Raises
    ------
    AlpesDynError
        ``error`` with one line: empty name, missing, a directory, FIFO or device, over ``limit``, unreadable.
    """
    p = _path(path, what, error)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(os.fspath(path), flags)  # as given: Path() drops a trailing '/' ('rec.csv/' is no file)
    except IsADirectoryError:
        raise error(f"{what} {str(p)!r}: is a directory, expected a file") from None
    except NotADirectoryError:
        raise error(f"{what} {os.fspath(path)!r}: a path through a file that is not a directory") from None
    except (OSError, ValueError, OverflowError) as exc:
        raise error(f"{what} {str(p)!r}: cannot be read ({getattr(exc, 'strerror', None) or exc})") from None
    try:
        st = os.fstat(fd)
        if stat.S_ISDIR(st.st_mode):
            raise error(f"{what} {str(p)!r}: is a directory, expected a file")
        if not stat.S_ISREG(st.st_mode):
            raise error(f"{what} {str(p)!r}: is {_kind(st.st_mode)}, expected a regular file")
        if st.st_size > limit:
            raise error(f"{what} {str(p)!r}: {st.st_size} bytes, over the limit of {limit} bytes for this kind of file")
        try:
            os.set_blocking(fd, True)
            with os.fdopen(os.dup(fd), "rb") as f:
                data = f.read(limit + 1)
        except OSError as exc:
            raise error(f"{what} {str(p)!r}: cannot be read ({exc.strerror or exc})") from None
        if len(data) > limit:  # grew while being read
            raise error(f"{what} {str(p)!r}: over the limit of {limit} bytes for this kind of file")
        return data
    finally:
        os.close(fd)


def decode_utf8(data: bytes, what: str, error: type[AlpesDynError] = InputError) -> str:
    """``data`` as UTF-8 text, a leading byte-order mark dropped.

    Parameters
    ----------
    data : bytes
        The bytes.
    what : str
        How the error names their source.
    error : type, optional
        The :class:`~alpes_dyn.errors.AlpesDynError` subclass raised (default InputError).

    Returns
    -------
    str
        The text.

    Raises
    ------
    AlpesDynError
        ``error`` naming the first bad byte and its offset.
    """
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise error(f"{what}: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start})") from None


def read_text(path: str | os.PathLike[str], what: str, error: type[AlpesDynError] = InputError,
              limit: int = MAX_TEXT_BYTES) -> str:
    """The content of a UTF-8 text file (a leading byte-order mark is accepted and dropped).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str
        How the error names the file, e.g. ``"parameter file"``.
    error : type, optional
        The :class:`~alpes_dyn.errors.AlpesDynError` subclass raised (default InputError).
    limit : int, optional
        The largest accepted size, bytes (default :data:`alpes_dyn.limits.MAX_TEXT_BYTES`).

    Returns
    -------
    str
        The text.

    Raises
    ------
    AlpesDynError
        ``error`` with one line: empty name, missing, a directory, FIFO or device, over ``limit``, unreadable, or
        not UTF-8 text (with the offset of the first bad byte).
    """
    data = read_bytes(path, what, error, limit)
    return decode_utf8(data, f"{what} {os.fspath(path)!r}", error)


def _toml_depth(text: str) -> int:
    """Deepest nesting of ``[`` / ``{`` in TOML text outside strings and comments (a bound checked
    before the parser, whose recursion a 100,000-deep array would exhaust)."""
    depth = deepest = 0
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c in "\"'":
            triple = text.startswith(c * 3, i)
            end = c * 3 if triple else c
            j = i + len(end)
            while j < n and not text.startswith(end, j):
                if c == '"' and text[j] == "\\":
                    j += 1
                elif not triple and text[j] == "\n":
                    break
                j += 1
            i = j + len(end)
            continue
        if c == "#":
            j = text.find("\n", i)
            i = n if j < 0 else j + 1
            continue
        if c in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif c in "]}":
            depth = max(depth - 1, 0)
        i += 1
    return deepest


def load_toml(text: str, what: str, error: type[AlpesDynError] = InputError) -> dict:
    """Parse TOML ``text`` with the limits of :mod:`alpes_dyn.limits` checked: nesting at most
    :data:`~alpes_dyn.limits.MAX_TOML_DEPTH` deep (before parsing), integers at most
    :data:`~alpes_dyn.limits.MAX_TOML_INT` in magnitude.

    Parameters
    ----------
    text : str
        The TOML text.
    what : str
        How the error names its source.
    error : type, optional
        The :class:`~alpes_dyn.errors.AlpesDynError` subclass raised (default InputError).

    Returns
    -------
    dict
        The parsed tables.

    Raises
    ------
    AlpesDynError
        ``error`` naming ``what``: invalid TOML, nested too deep, or an integer too large.
    """
    import tomllib

    from .limits import MAX_TOML_DEPTH, MAX_TOML_INT

    if _toml_depth(text) > MAX_TOML_DEPTH:
        raise error(f"{what}: arrays or tables nested more than {MAX_TOML_DEPTH} deep")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{what}: invalid TOML ({exc})") from None
    except (RecursionError, MemoryError, ValueError) as exc:  # ValueError: Python's int-digit limit
        raise error(f"{what}: invalid TOML ({type(exc).__name__}: {str(exc)[:100]})") from None

    def walk(x: object, where: str) -> None:
        if isinstance(x, dict):
            for k, v in x.items():
                walk(v, f"{where}.{k}" if where else str(k))
        elif isinstance(x, list):
            for v in x:
                walk(v, where)
        elif isinstance(x, int) and not isinstance(x, bool) and abs(x) > MAX_TOML_INT:
            raise error(f"{what}: {where}: integer of {len(str(abs(x)))} digits, over the limit of {MAX_TOML_INT}")

    walk(data, "")
    return data


# ----------------------------------------------------------------------------- signals
class Terminated(BaseException):
    """Raised in the main thread by a caught SIGTERM/SIGHUP inside :func:`signals_as_exceptions`."""

    def __init__(self, signum: int) -> None:
        super().__init__(f"terminated by signal {signum}")
        self.signum = signum


_CAUGHT = tuple(s for s in (getattr(signal, "SIGTERM", None), getattr(signal, "SIGHUP", None)) if s is not None)
_depth = 0


def _raise_terminated(signum: int, frame: object) -> None:
    raise Terminated(signum)


@contextlib.contextmanager
def signals_as_exceptions() -> Iterator[None]:
    """Inside the block, SIGTERM and SIGHUP raise :class:`Terminated` (SIGINT already raises
    ``KeyboardInterrupt``), so that ``finally`` clauses remove temporary files; when the block ends by
    such a signal, the previous handler is put back and the signal sent again, so the process ends
    as it would have (killed by that signal). Only in the main thread and only for signals whose
    handler is the default one (a program's own handlers are left alone); a no-op elsewhere."""
    global _depth
    if threading.current_thread() is not threading.main_thread() or _depth:
        yield
        return
    saved: dict[int, object] = {}
    for s in _CAUGHT:
        try:
            if signal.getsignal(s) is signal.SIG_DFL:
                saved[s] = signal.signal(s, _raise_terminated)
        except (OSError, ValueError):
            pass
    _depth += 1
    try:
        yield
    except Terminated as exc:
        _restore(saved)
        saved = {}
        os.kill(os.getpid(), exc.signum)  # die by the signal, as without the handler
        raise
    finally:
        _depth -= 1
        _restore(saved)


def _restore(saved: dict[int, object]) -> None:
    for s, h in saved.items():
        try:
            signal.signal(s, h)  # type: ignore[arg-type]
        except (OSError, ValueError):
            pass


# ----------------------------------------------------------------------------- output policy
def _same_file(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):
        return os.path.realpath(os.path.abspath(a)) == os.path.realpath(os.path.abspath(b))


def _check_destination(p: Path, what: str, error: type[AlpesDynError]) -> None:
    """An existing destination must be a regular file, not a link (checked again just before the rename)."""
    try:
        st = os.lstat(p)
    except (FileNotFoundError, NotADirectoryError):
        return  # the directory checks (or the write) name the problem
    except OSError as exc:
        raise error(f"{what}: cannot write {str(p)!r} ({exc.strerror or exc})") from None
    if stat.S_ISLNK(st.st_mode):
        raise error(f"{what}: {str(p)!r} is a symbolic link; refusing to replace it (give the file it points to)")
    if stat.S_ISDIR(st.st_mode):
        raise error(f"{what}: {str(p)!r} is a directory, expected a file name")
    if not stat.S_ISREG(st.st_mode):
        raise error(f"{what}: {str(p)!r} is {_kind(st.st_mode)}; only a regular file is written (or replaced)")


def writable_directory(p: Path) -> bool:
    """Whether the directory ``p`` can take new files: ``os.access`` (which root always passes) and a write bit in
    its mode (a directory made read-only, 0555, is refused to root too: nothing is written where the mode says
    no).

    Parameters
    ----------
    p : pathlib.Path
        The directory.

    Returns
    -------
    bool
        True where new files can be written in it.
    """
    try:
        return os.access(p, os.W_OK | os.X_OK) and bool(os.stat(p).st_mode & 0o222)
    except OSError:
        return False


def _check_extension(p: Path, what: str, extensions: Sequence[str], error: type[AlpesDynError]) -> None:
    ext = p.suffix.lower().lstrip(".")
    if ext not in extensions:
        raise error(f"{what}: {str(p)!r} has {'extension ' + repr(ext) if ext else 'no extension'}; "
                    f"expected one of {', '.join('.' + e for e in extensions)}")


def _check_output_name(p: Path, what: str, error: type[AlpesDynError]) -> None:
    """An output's own name (the last component): at most 255 bytes (the file systems' NAME_MAX: a longer one
    made ``os.stat`` raise, an internal error), and no control character (a line break or an escape in a name the
    command would create: a file nobody can type back)."""
    name = p.name
    if len(os.fsencode(name)) > 255:
        raise error(f"{what}: the name {name[:40]!r}... has {len(os.fsencode(name))} bytes, over the 255 a file "
                    "name may have")
    if any(ord(ch) < 32 or ord(ch) == 127 for ch in name):
        raise error(f"{what}: the name {name[:80]!r} holds a control character (a line break, a tab, an escape); "
                    "give a printable name")


def check_output_path(path: str | None, what: str, extensions: Sequence[str] | None = None,
                      error: type[AlpesDynError] = InputError) -> Path:
    """Validate one output file name before any work: not empty, not ending in ``/``, not an existing
    directory, device, FIFO or symbolic link, its directory exists and is writable, and (if given) its
    extension is one of ``extensions`` (lower-case, without dot).

    Parameters
    ----------
    path : str or None
        The output file's name (None: refused as empty).
    what : str
        The option or field the error names.
    extensions : sequence of str or None, optional
        The accepted extensions, lower-case, without dot (default None: any).
    error : type, optional
        The :class:`~alpes_dyn.errors.AlpesDynError` subclass raised (default InputError).

    Returns
    -------
    pathlib.Path
        The path.

    Raises
    ------
    AlpesDynError
        ``error`` with one line naming ``what``.
    """
    p = _path(path if path is not None else "", what, error)
    text = os.fspath(path)  # type: ignore[arg-type]
    _check_output_name(p, what, error)
    if text.endswith(("/", os.sep)) and not p.is_dir():
        raise error(f"{what}: {text!r} ends with '/': it names a directory, expected a file name")
    _check_destination(p, what, error)
    if extensions is not None:
        _check_extension(p, what, extensions, error)
    parent = p.parent if str(p.parent) else Path(".")
    if parent.exists() and not parent.is_dir():
        raise error(f"{what}: {str(parent)!r} in {str(p)!r} is not a directory")
    if not parent.is_dir():
        raise error(f"{what}: directory {str(parent)!r} of {str(p)!r} does not exist")
    if not writable_directory(parent):
        raise error(f"{what}: directory {str(parent)!r} is not writable")
    return p


def check_outputs(outputs: Sequence[tuple[str, str | os.PathLike[str] | None]],
                  inputs: Sequence[tuple[str, str | os.PathLike[str] | None]] = (),
                  extensions: dict[str, Sequence[str]] | None = None,
                  error: type[AlpesDynError] = InputError) -> list[Path]:
    """The output policy of a run, checked before any work (one call per command).

    Parameters
    ----------
    outputs : sequence of tuple of (str, str or os.PathLike or None)
        (option, path) of every file the run may write (None: not asked for).
    inputs : sequence of tuple of (str, str or os.PathLike or None), optional
        (option, path) of every file the run reads (None: the shipped default; default none).
    extensions : dict of str to sequence of str, or None, optional
        Option -> accepted extensions, for the outputs whose format is chosen by it (default None).
    error : type, optional
        The :class:`~alpes_dyn.errors.AlpesDynError` subclass raised (default InputError).

    Returns
    -------
    list of pathlib.Path
        The outputs asked for, in order.

    Raises
    ------
    InputError
        (or ``error``) with one line naming the option: an output that is one of the inputs (the same
        file, compared by device and inode, so a hard link or another spelling counts) or the same path
        as another output, and every refusal of :func:`check_output_path`.
    """
    done: list[tuple[str, Path]] = []
    for opt, path in outputs:
        if path is None:
            continue
        p = check_output_path(path, opt, None, error)  # (its format by extension after: an input's name first)
        for iopt, ipath in inputs:
            if ipath is None or not isinstance(ipath, (str, os.PathLike)) or not os.fspath(ipath):
                continue
            if os.path.exists(p) and _same_file(p, Path(ipath)):
                raise error(f"{opt}: {str(p)!r} is the input of {iopt}; refusing to write over it (choose another "
                            "file name)")
        for oopt, q in done:
            if _same_file(p, q):
                raise error(f"{opt}: {str(p)!r} is also the output of {oopt}; give each output its own file")
        done.append((opt, p))
    for opt, p in done:  # the formats last: an output on an input or on another output is the first thing said
        if (extensions or {}).get(opt) is not None:
            _check_extension(p, opt, extensions[opt], error)  # type: ignore[index]
    return [p for _, p in done]


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], what: str = "output",
                error: type[AlpesDynError] = InputError) -> Iterator[Path]:
    """Context manager yielding a temporary path next to ``path``; renamed over ``path`` on success.

    The temporary file keeps ``path``'s extension (for writers that choose the format by it, e.g.
    matplotlib) and is flushed to disk before the rename; on any exception, and on SIGINT, SIGTERM or
    SIGHUP (:func:`signals_as_exceptions`), it is removed and the destination is left as it was. An
    existing destination that is a symbolic link, a directory, a device or a FIFO is refused
    (``error``) and never replaced. ``OSError`` becomes ``error`` naming ``what`` and the path.

    Parameters
    ----------
    path : str or os.PathLike
        The destination file.
    what : str, optional
        The option or field the error names (default ``"output"``).
    error : type, optional
        The :class:`~alpes_dyn.errors.AlpesDynError` subclass raised (default InputError).

    Yields
    ------
    pathlib.Path
        The temporary path to write.
    """
    dest = _path(path, what, error)
    if os.fspath(path).endswith(("/", os.sep)):  # type: ignore[arg-type]
        raise error(f"{what}: {os.fspath(path)!r} ends with '/': it names a directory, expected a file name")
    _check_destination(dest, what, error)
    parent = dest.parent
    if parent.is_dir() and not writable_directory(parent):  # (a 0555 folder: refused to root too, as the CLI does)
        raise error(f"{what}: directory {str(parent)!r} is not writable")
    with signals_as_exceptions():
        try:
            # the name shortened so that the temporary name fits where the destination's does (255 bytes)
            fd, tmp = tempfile.mkstemp(prefix=f".{dest.stem[:80]}.", suffix=f".tmp{dest.suffix[:16]}", dir=parent)
        except OSError as exc:
            raise error(f"{what}: cannot write {str(dest)!r} ({exc.strerror or exc})") from None
        os.close(fd)
        tmp_path = Path(tmp)
        try:
            yield tmp_path
            with open(tmp_path, "rb+") as f:  # the writer may have closed the file: flush it to disk here
                os.fsync(f.fileno())
            os.chmod(tmp_path, 0o666 & ~_UMASK)  # mkstemp makes 0o600; a written file gets the usual mode
            _check_destination(dest, what, error)  # not replaced by a link or a device meanwhile
            os.replace(tmp_path, dest)
        except OSError as exc:
            _unlink(tmp_path)
            raise error(f"{what}: cannot write {str(dest)!r} ({exc.strerror or exc})") from None
        except BaseException:
            _unlink(tmp_path)
            raise
    _fsync_dir(parent)


def atomic_write(path: str | os.PathLike[str], data: str | bytes, what: str = "output",
                 error: type[AlpesDynError] = InputError) -> Path:
    """Write ``data`` to ``path`` atomically (see :func:`atomic_path`).

    Parameters
    ----------
    path : str or os.PathLike
        The destination file.
    data : str or bytes
        The content (str written as UTF-8).
    what : str, optional
        The option or field the error names (default ``"output"``).
    error : type, optional
        The :class:`~alpes_dyn.errors.AlpesDynError` subclass raised (default InputError).

    Returns
    -------
    pathlib.Path
        The path written.
    """
    payload = data.encode("utf-8") if isinstance(data, str) else bytes(data)
    with atomic_path(path, what, error) as tmp:
        with open(tmp, "wb") as f:
            f.write(payload)
            f.flush()
            os.fsync(f.fileno())
    return Path(path)


def check_output_directory(directory: str | os.PathLike[str] | None, what: str = "-o") -> Path:
    """A directory to create: not empty, not an existing file, link or non-empty directory, its parent an
    existing writable directory.

    Parameters
    ----------
    directory : str or os.PathLike or None
        The directory's name.
    what : str, optional
        The option the error names (default ``"-o"``).

    Returns
    -------
    pathlib.Path
        The directory's path (a trailing ``/`` dropped).

    Raises
    ------
    InputError
        One line naming ``what``.
    """
    text = os.fspath(directory) if isinstance(directory, (str, os.PathLike)) else ""
    if not text or "\0" in text:
        raise InputError(f"{what}: expected a directory name, got {text!r}")
    p = Path(text.rstrip("/") or "/")
    _check_output_name(p, what, InputError)
    if os.path.islink(p):
        raise InputError(f"{what}: {text!r} is a symbolic link; give a new directory name")
    if p.exists():
        if not p.is_dir():
            raise InputError(f"{what}: {text!r} exists and is not a directory; give a new directory name")
        if any(p.iterdir()):
            raise InputError(f"{what}: directory {text!r} is not empty; refusing to write over it (give a new "
                             "directory name)")
        if p.resolve() == p.resolve().parent:
            raise InputError(f"{what}: {text!r} is the root directory")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise InputError(f"{what}: directory {str(parent)!r} of {text!r} does not exist")
    if not writable_directory(parent):
        raise InputError(f"{what}: directory {str(parent)!r} is not writable")
    return p


def write_directory(files: dict[str, str], directory: str | os.PathLike[str], what: str = "-o") -> dict[str, Path]:
    """Write ``files`` ({name: text}) into ``directory``, a new (or empty) directory: into a temporary directory
    beside it first, which is then renamed to ``directory`` (never a partial directory; an error or an
    interruption leaves nothing): the directory's twin of :func:`atomic_path`.

    Parameters
    ----------
    files : dict of str to str
        {plain file name: text}.
    directory : str or os.PathLike
        The new (or empty) directory (:func:`check_output_directory`).
    what : str, optional
        The option the error names (default ``"-o"``).

    Returns
    -------
    dict of str to pathlib.Path
        {file name: path written}.

    Raises
    ------
    InputError
        A bad directory or file name, or a write that fails, one line.
    """
    dest = check_output_directory(directory, what)
    for name, text in files.items():
        if not isinstance(name, str) or not name or "/" in name or "\0" in name or name.startswith(".") \
                or len(name.encode("utf-8", "replace")) > 255:
            raise InputError(f"files: {name!r:.80} is not a plain file name")
        if not isinstance(text, str):
            raise InputError(f"files: {name!r}'s content is {type(text).__name__}, expected str (text)")
    with signals_as_exceptions():
        tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name[:80]}.", suffix=".tmp", dir=dest.parent))
        try:
            for name, text in files.items():
                _write_file(tmp / name, text)
            os.chmod(tmp, 0o777 & ~_UMASK)
            check_output_directory(dest, what)  # nothing came there meanwhile
            os.rename(tmp, dest)  # replaces an empty directory, atomically
        except OSError as exc:
            shutil.rmtree(tmp, ignore_errors=True)
            raise InputError(f"{what}: cannot write {str(dest)!r} ({exc.strerror or exc})") from None
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
    _fsync_dir(dest.parent)
    return {name: dest / name for name in files}


def _write_file(path: Path, text: str) -> None:
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())


@contextlib.contextmanager
def native_stderr_to(sink: list[str]) -> Iterator[None]:
    """Capture what native code writes to file descriptor 2 inside the block; its lines are appended
    to ``sink`` (Python's ``sys.stderr`` is flushed first and is captured as well). A closed file
    descriptor 2 (``2>&-``) is left closed: nothing is captured.

    Parameters
    ----------
    sink : list of str
        The list the captured lines (stripped, non-empty) are appended to.
    """
    fd = 2  # the process's standard error, whatever sys.stderr is
    try:
        saved = os.dup(fd)
    except OSError as exc:
        if exc.errno != errno.EBADF:
            raise
        yield
        return
    try:
        sys.stderr.flush()
    except (OSError, ValueError, AttributeError):
        pass
    with tempfile.TemporaryFile() as tmp:
        try:
            os.dup2(tmp.fileno(), fd)
            yield
        finally:
            try:
                sys.stderr.flush()
            except (OSError, ValueError, AttributeError):
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
