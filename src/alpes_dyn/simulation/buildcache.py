"""The on-disk cache of compiled shared libraries: checked, locked and self-healing.

:func:`build_library` compiles C source once into ``<stem>_<key>.so`` in a cache directory (``key``:
a hash of the source, the compiler and its flags) and returns it loaded with :mod:`ctypes`:

* **checked before it is loaded** -- beside each library a small file ``<stem>_<key>.so.sha256``
  records its size, its SHA-256 and the ``key`` it was built for (the hash of the generated source,
  which is the model's structure, with the compiler and flags); a library is loaded only if all three
  match. A library truncated by a full disk or a killed copy, with a flipped byte, without its record,
  with a record of an older alpes_dyn (no key), or copied with its record under another model's name
  (``malloc(): invalid size`` once called with the wrong sizes) is never handed to the dynamic loader
  (which would crash the process with a bus error or a segmentation fault): it is removed and
  compiled again;
* **locked** -- a build holds an exclusive ``fcntl`` lock on ``<stem>_<key>.lock``, so that
  concurrent processes (or threads) needing the same library compile it once; the others wait and
  load the result;
* **atomic** -- the compiler writes into a private build folder ``.build@<stem>_<key>@...`` (its own
  temporary files too: ``TMPDIR`` points there for the compiler's process); the
  finished library is flushed to disk and renamed into place, then its record is written (also by
  rename), so a reader never sees a half-written file;
* **cleaned** -- a build stopped by SIGINT, SIGTERM or SIGHUP removes its folder (and stops the
  compiler); build folders left by killed builds (SIGKILL: their lock is free) are removed by the next
  build, as are ``tmp*`` folders older than an hour left by versions before this cache.

Errors are :class:`CompilerError` with one line.
"""

from __future__ import annotations

import contextlib
import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any, Iterator, Sequence

from ..errors import AlpesDynError
from ..fileio import atomic_write, signals_as_exceptions

try:  # POSIX; elsewhere builds are not locked
    import fcntl
except ImportError:  # pragma: no cover - not POSIX
    fcntl = None  # type: ignore[assignment]

__all__ = ["CompilerError", "build_library", "cached_library", "verify_library", "expression_key", "LEGACY_TMP_AGE_S"]

LEGACY_TMP_AGE_S = 3600.0
"""Age (s) after which a ``tmp*`` folder of an older alpes_dyn in the cache is removed."""

_BUILD = ".build@"


class CompilerError(AlpesDynError, RuntimeError):
    """The C compiler is missing or failed on generated code, or the cache cannot be used."""


def expression_key(function: Any) -> str:
    """The key of a CasADi function's expression: the SHA-1 of its serialised form (hex, 40 characters). Two
    functions of one key generate the same C, so the code compiled or generated for one serves the other (the
    compiled loops of :mod:`~alpes_dyn.simulation.sampled` and of the observer's predictions, the C library's source
    of :mod:`~alpes_dyn.estimation.cexport.cexport`).

    Parameters
    ----------
    function : casadi.Function
        The function (its numbers included in the expression: a parameter vector kept as an input shares the key).

    Returns
    -------
    str
        The key.
    """
    return hashlib.sha1(function.serialize().encode()).hexdigest()


def _digest(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _record_path(lib: Path) -> Path:
    return lib.with_name(lib.name + ".sha256")


def _name_key(lib: Path) -> str:
    """The key in a library's file name ``<stem>_<key>.so``."""
    return lib.name.removesuffix(".so").rsplit("_", 1)[-1]


def verify_library(lib: Path, key: str | None = None) -> bool:
    """True if ``lib`` exists, its size and SHA-256 equal its record, and the record's ``model`` key is
    ``key`` (default: the key in the file's own name, ``<stem>_<key>.so``): the library is the one
    built for this source, not another model's copied under its name (no loading).

    Parameters
    ----------
    lib : pathlib.Path
        The library, ``<stem>_<key>.so``, its record ``<lib>.sha256`` beside it.
    key : str or None, optional
        The expected key (default None: the one in the file's name).

    Returns
    -------
    bool
        Whether the library is the one recorded.
    """
    try:
        fields = _record_path(lib).read_text(encoding="ascii").split()
        rec = dict(zip(fields[::2], fields[1::2]))
        if rec.get("model") != (_name_key(lib) if key is None else key):
            return False
        if lib.stat().st_size != int(rec["size"]):
            return False
        return _digest(lib) == rec["sha256"]
    except (OSError, ValueError, KeyError, UnicodeDecodeError):
        return False


def _load(lib: Path, key: str) -> ctypes.CDLL | None:
    """The library loaded if it passes :func:`verify_library` for ``key``, else None."""
    if not verify_library(lib, key):
        return None
    try:
        return ctypes.CDLL(str(lib))
    except OSError:
        return None


@contextlib.contextmanager
def _locked(path: Path, blocking: bool = True) -> Iterator[bool]:
    """Hold an exclusive lock on ``path`` (created if needed); yields False if not blocking and busy."""
    if fcntl is None:  # pragma: no cover - not POSIX
        yield True
        return
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    except OSError as exc:
        raise CompilerError(f"cache lock {str(path)!r}: cannot be created ({exc.strerror or exc})") from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | (0 if blocking else fcntl.LOCK_NB))
        except BlockingIOError:
            yield False
            return
        try:
            yield True
        finally:
            fcntl.flock(fd, fcntl.LOCK_UN)
    finally:
        os.close(fd)


def _clean_stale(d: Path, own: str) -> None:
    """Remove build folders of killed builds: those of ``own`` (whose lock the caller holds) and those
    whose lock is free; and ``tmp*`` folders of older versions after :data:`LEGACY_TMP_AGE_S`."""
    now = time.time()
    try:
        entries = list(d.iterdir())
    except OSError:
        return
    for e in entries:
        try:
            if not e.is_dir():
                continue
            if e.name.startswith(_BUILD):
                name = e.name[len(_BUILD):].split("@", 1)[0]
                if name == own:
                    shutil.rmtree(e, ignore_errors=True)
                    continue
                with _locked(d / f"{name}.lock", blocking=False) as free:
                    if free:
                        shutil.rmtree(e, ignore_errors=True)
            elif e.name.startswith("tmp") and now - e.stat().st_mtime > LEGACY_TMP_AGE_S:
                shutil.rmtree(e, ignore_errors=True)
        except (OSError, CompilerError):
            continue


def _remove(*paths: Path) -> None:
    for p in paths:
        try:
            p.unlink()
        except FileNotFoundError:
            pass
        except OSError as exc:
            raise CompilerError(f"cache: cannot remove the broken {str(p)!r} ({exc.strerror or exc})") from None


def _source_key(source: str, cc: str, cflags: Sequence[str]) -> str:
    """The key of a build: a hash of the source, the flags and the compiler's name (20 hex characters)."""
    return hashlib.sha256((source + "\0" + " ".join(cflags) + "\0" + os.path.basename(cc)).encode()).hexdigest()[:20]


def _find(lib: Path, key: str) -> tuple[Path, bool, float, ctypes.CDLL] | None:
    """The verified library of ``key`` loaded: ``lib`` itself, or the same source built under another stem (the
    hand's fingers); None if there is none."""
    handle = _load(lib, key)
    if handle is not None:
        return lib, False, 0.0, handle
    for same in sorted(lib.parent.glob(f"*_{key}.so")):
        handle = _load(same, key)
        if handle is not None:
            return same, False, 0.0, handle
    return None


def cached_library(source: str, stem: str, cc: str, cflags: Sequence[str],
                   directory: Path) -> tuple[Path, bool, float, ctypes.CDLL] | None:
    """The library :func:`build_library` would return for these arguments if it is in the cache already (verified
    and loaded), else None: nothing is compiled, nothing is written.

    Parameters
    ----------
    source : str
        The C source.
    stem : str
        The file name's stem.
    cc : str
        The compiler's path.
    cflags : sequence of str
        Compiler flags.
    directory : pathlib.Path
        The cache's folder (need not exist).

    Returns
    -------
    tuple or None
        ``(path, False, 0.0, library)`` as :func:`build_library`'s, or None when the cache holds no verified
        library of this source, compiler and flags.
    """
    key = _source_key(source, cc, cflags)
    return _find(Path(directory) / f"{stem}_{key}.so", key)


def build_library(source: str, stem: str, cc: str, cflags: Sequence[str], directory: Path,
                  libs: Sequence[str] = ("-lm",)) -> tuple[Path, bool, float, ctypes.CDLL]:
    """Compile ``source`` into a shared library in ``directory`` once, and load it.

    Parameters
    ----------
    source : str
        The C source.
    stem : str
        The file name's stem (letters, digits, ``_``).
    cc : str
        The compiler's path.
    cflags : sequence of str
        Compiler flags (must produce a shared library).
    directory : pathlib.Path
        The cache's folder.
    libs : sequence of str, optional
        Libraries linked (default ``("-lm",)``).

    Returns
    -------
    path : pathlib.Path
        The library.
    compiled_now : bool
        False when a verified library was
        loaded from the cache (``seconds`` 0), True when this call compiled it. A verified library of the same
        ``key`` (the same source, compiler and flags) built under another ``stem`` is loaded, not compiled again:
        ``path`` is then that library's.
    seconds : float
        The compile's wall time, s.
    library : ctypes.CDLL
        The loaded library.

    Raises
    ------
    CompilerError
        The compiler is missing or fails, or the cache cannot be used.
    """
    key = _source_key(source, cc, cflags)
    name = f"{stem}_{key}"
    d = Path(directory)
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CompilerError(f"cache directory {str(d)!r}: cannot be created ({exc.strerror or exc})") from None
    lib = d / f"{name}.so"
    found = _find(lib, key)
    if found is not None:
        return found
    with _locked(d / f"{name}.lock"):
        _clean_stale(d, name)
        handle = _load(lib, key)  # built by another process while this one waited
        if handle is not None:
            return lib, False, 0.0, handle
        _remove(lib, _record_path(lib))  # missing, broken or unloadable: build it again
        t0 = time.perf_counter()
        with signals_as_exceptions():  # SIGTERM/SIGHUP: the build folder removed, the compiler stopped
            return _build_locked(source, stem, cc, cflags, d, libs, key, lib, t0)


def _build_locked(source: str, stem: str, cc: str, cflags: Sequence[str], d: Path, libs: Sequence[str], key: str,
                  lib: Path, t0: float) -> tuple[Path, bool, float, ctypes.CDLL]:
    """The compilation of :func:`build_library`, its lock held: in a private build folder, renamed into place."""
    name = f"{stem}_{key}"
    try:
        build = Path(tempfile.mkdtemp(prefix=f"{_BUILD}{name}@", dir=d))
    except OSError as exc:
        raise CompilerError(f"cache directory {str(d)!r}: not writable ({exc.strerror or exc})") from None
    try:
        c = build / f"{stem}.c"
        c.write_text(source, encoding="utf-8")
        out = build / f"{stem}.so"
        env = dict(os.environ, TMPDIR=str(build))  # gcc's own temporary files (cc*.s, cc*.o) in the build folder
        try:
            proc = subprocess.run([cc, *cflags, str(c), "-o", str(out), *libs], capture_output=True, text=True,
                                  env=env)
        except OSError as exc:
            raise CompilerError(f"C compiler {cc!r} cannot be run ({exc.strerror or exc}; set CC)") from None
        if proc.returncode != 0:
            first = (proc.stderr.strip().splitlines() or ["unknown error"])[0]
            raise CompilerError(f"compiling {stem}.c failed: {first}")
        with open(out, "rb+") as f:
            os.fsync(f.fileno())
        size, digest = out.stat().st_size, _digest(out)
        os.replace(out, lib)  # atomic: a reader sees the old state or the whole library
        atomic_write(_record_path(lib), f"sha256 {digest}\nsize {size}\nmodel {key}\n", "cache record")
    except OSError as exc:
        raise CompilerError(f"cache: cannot write {name}.so ({exc.strerror or exc})") from None
    except AlpesDynError as exc:
        if isinstance(exc, CompilerError):
            raise
        raise CompilerError(f"cache: {exc}") from None
    finally:
        shutil.rmtree(build, ignore_errors=True)
    handle = _load(lib, key)
    if handle is None:
        raise CompilerError(f"cache: the freshly built {str(lib)!r} cannot be loaded")
    return lib, True, time.perf_counter() - t0, handle
