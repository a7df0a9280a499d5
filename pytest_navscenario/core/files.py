"""Writing files safely: atomic whole-file writes with the usual permissions, one writer at a
time (``WriterLock``), JSON-safe values, and file names that are safe on every platform. Shared by
every layer that writes."""
from __future__ import annotations

import hashlib
import math
import os
import re
import tempfile
from pathlib import Path
from typing import Any


def json_safe(value: Any) -> Any:
    """Strict-JSON copy: non-finite floats become null (JSON has no NaN/inf)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    return value


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` to ``path`` via a temporary file in the same folder and an atomic rename."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            os.fchmod(fh.fileno(), usual_mode())  # mkstemp makes 0600; give the usual mode
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def data_file_size(path: Path, error: type[Exception], limit: int, advice: str) -> int:
    """The size in bytes of a data file a scenario names (a mesh, a heightfield), checked before
    anything reads it: ``error`` (the caller's error class) when it is missing, unreadable, not a
    regular file (a folder, a named pipe: reading one would hang), or larger than ``limit`` bytes
    (the message ends with ``advice``, what to do about it)."""
    try:
        size = path.stat().st_size
    except FileNotFoundError:
        raise error(f"{path} does not exist") from None
    except OSError as exc:
        raise error(f"{path} cannot be read: {exc.strerror or exc}") from None
    if not path.is_file():
        raise error(f"{path} is not a file")
    if size > limit:
        raise error(f"{path.name} is {size / 1e6:.1f} MB, more than the limit of {limit / 1e6:.0f} MB; {advice}")
    return size


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def usual_mode() -> int:
    """The mode a new file gets from ``open`` (0666 less the umask): what a file written through a
    temporary one (mkstemp makes 0600) must be given before it is renamed into place."""
    return 0o666 & ~_umask()


_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


def folder_name(nodeid: str) -> str:
    """A file-system-safe, unique folder name for a node id."""
    readable = _UNSAFE.sub("_", nodeid).strip("._-")[:80] or "item"
    digest = hashlib.sha1(nodeid.encode("utf-8")).hexdigest()[:8]
    return f"{readable}-{digest}"


class FileBusy(OSError):
    """Another process holds the lock of a file (its holder's own words are in ``holder``)."""

    def __init__(self, path: Path, holder: str):
        super().__init__(f"{path} is locked by {holder or 'another process'}")
        self.path, self.holder = path, holder


class WriterLock:
    """One writer at a time for ``path``: an exclusive, non-blocking lock on the hidden file
    ``.<name>.lock`` beside it, holding the holder's description (pid, host, start time, command)
    for the message a second writer gets. The operating system drops the lock when the holder
    dies, even by SIGKILL, so a stale lock file never blocks anyone; ``release`` removes it.

    Why a lock file and not the file itself: the file is replaced by an atomic rename, so a lock
    on it would stay on the old inode."""

    def __init__(self, path: str | os.PathLike, description: str):
        self.path = Path(path)
        self.lock_path = self.path.with_name(f".{self.path.name}.lock")
        self._fd: int | None = None
        while self._fd is None:
            fd = os.open(self.lock_path, os.O_RDWR | os.O_CREAT, 0o666)
            try:
                if not _try_lock(fd):
                    raise FileBusy(self.path, _read_holder(fd))
                # the holder may have removed the file between our open and our lock: then again
                if os.fstat(fd).st_ino == os.stat(self.lock_path).st_ino:
                    os.ftruncate(fd, 0)
                    os.lseek(fd, 0, os.SEEK_SET)
                    os.write(fd, description.encode("utf-8"))
                    self._fd, fd = fd, -1
            except FileNotFoundError:
                pass                                  # removed under us: take a new one
            finally:
                if fd >= 0:
                    os.close(fd)

    def release(self) -> None:
        fd, self._fd = self._fd, None
        if fd is None:
            return
        try:
            os.unlink(self.lock_path)                 # while still held: nobody can lock it meanwhile
            os.close(fd)
        except OSError:                               # Windows: an open file cannot be removed
            os.close(fd)
            try:
                os.unlink(self.lock_path)
            except OSError:
                pass


def _read_holder(fd: int) -> str:
    try:
        os.lseek(fd, 0, os.SEEK_SET)
        return os.read(fd, 4096).decode("utf-8", "replace").strip()
    except OSError:                                   # Windows: the holder's lock covers it
        return ""


def _try_lock(fd: int) -> bool:
    """Lock ``fd`` exclusively without waiting; False if someone else holds it."""
    try:
        import fcntl
    except ImportError:                               # Windows
        import msvcrt
        try:
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
            return True
        except OSError:
            return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return True
    except BlockingIOError:
        return False
