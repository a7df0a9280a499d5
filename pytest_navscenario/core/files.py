"""Writing files safely: atomic whole-file writes with the usual permissions, JSON-safe values,
and file names that are safe on every platform. Shared by every layer that writes."""
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
