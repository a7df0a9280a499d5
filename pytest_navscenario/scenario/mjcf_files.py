"""The files an MJCF robot is made of: the file itself and those it names (meshes, textures,
heightfields, skins, included files, recursively), found by reading its XML (no MuJoCo), so that a
frozen failure can carry its robot beside it (``mjcf_files``), and so that the loader can check,
before MuJoCo opens any of them, that each follows ``robot.body.file``'s rules and hash them all
into the scenario's content (``robot_files``, ``robot_digest``).

Paths follow MuJoCo's rules: relative to the file's folder, under the compiler's ``assetdir`` and,
for meshes, heightfields and skins, ``meshdir`` (textures: ``texturedir``). Absolute paths and
paths leading out of the robot's folder are left out (they would not travel with it anyway).
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

MESH_LIKE = ("mesh", "hfield", "skin")


def mjcf_files(path: Path) -> list[Path]:
    """The MJCF file ``path`` and every file it names that exists inside its folder, in the order
    found (``path`` first), each once."""
    root_dir = path.parent.resolve()
    out: list[Path] = []
    todo = [path.resolve()]
    while todo:
        file = todo.pop(0)
        if file in out:
            continue
        out.append(file)
        if file.suffix.lower() != ".xml":
            continue
        try:
            tree = ET.parse(file)
        except (ET.ParseError, OSError):
            continue
        dirs = {"assetdir": "", "meshdir": "", "texturedir": ""}
        for compiler in tree.iter("compiler"):
            dirs.update({k: v for k, v in compiler.attrib.items() if k in dirs})
        for element in tree.iter():
            name = element.attrib.get("file")
            if not name or Path(name).is_absolute():
                continue
            sub = dirs["meshdir"] or dirs["assetdir"] if element.tag in MESH_LIKE else \
                dirs["texturedir"] or dirs["assetdir"] if element.tag == "texture" else ""
            found = (file.parent / sub / name).resolve()
            if found.is_file() and (found == root_dir or root_dir in found.parents):
                todo.append(found)
    return out


# ---------------------------------------------------------------- what MuJoCo will open, checked

MAX_ROBOT_BYTES = 256_000_000   # the MJCF and every file it names, together: read to be hashed
MAX_XML_FILES = 1_000           # included files (an include loop or a tree of them is cut short)
_SCHEME = ("://", "file:", "mem:", "http:", "https:")


class MjcfFileError(ValueError):
    """A file an MJCF robot names cannot be used: the message says which and why (the loader adds
    the scenario file, the line of ``robot.body.file`` and the fix)."""


def _regular(path: Path, what: str) -> int:
    """The size of ``path``, a regular file (a FIFO, a device or a folder is refused without being
    opened: reading one could hang); 0 when it does not exist (MuJoCo will say so)."""
    import stat
    try:
        st = path.stat()
    except FileNotFoundError:
        return 0
    except OSError as exc:
        raise MjcfFileError(f"{what} {path} cannot be read: {exc.strerror or exc}") from None
    if not stat.S_ISREG(st.st_mode):
        raise MjcfFileError(f"{what} {path} is not a regular file (a named pipe, a device or a folder)")
    return st.st_size


def _inside(folder: Path, value: str, bases: list[Path], what: str) -> list[Path]:
    """Each place MuJoCo may open ``value`` from (relative to each of ``bases``), all inside
    ``folder``: an absolute path, a URL-like name or one leading out (``..``, a link) is refused."""
    if not value:
        return []
    if Path(value).is_absolute() or value.startswith(("/", "\\")) or any(s in value for s in _SCHEME):
        raise MjcfFileError(f"{what} {value!r} is an absolute path or a URL; the robot's files must lie in "
                            f"the scenario's folder {folder}")
    out = []
    for base in bases:
        place = (base / value).resolve()
        if place != folder and folder not in place.parents:
            raise MjcfFileError(f"{what} {value!r} leads to {place}, outside the scenario's folder {folder}")
        out.append(place)
    return out


def robot_files(path: Path, folder: Path) -> list[Path]:
    """The MJCF file ``path`` and every file MuJoCo may open for it (included files, recursively;
    meshes, textures, heightfields, skins and models, under the compiler's meshdir, texturedir and
    assetdir), checked with ``robot.body.file``'s rules: inside ``folder`` (relative, no ``..`` or
    link out, no absolute path or URL; the compiler's folders too), regular files (a FIFO is
    refused without being opened). Files that do not exist are left to MuJoCo's own message.
    MjcfFileError says what is wrong."""
    folder, main = folder.resolve(), path.resolve()
    xml_files, dirs, total = _xml_files(main, folder)
    out = list(xml_files)
    for file, tree in xml_files.items():
        bases = [main.parent] + ([file.parent] if file.parent != main.parent else [])
        for element in tree.iter():
            for key, value in element.attrib.items():
                if not key.startswith("file") or element.tag == "include":
                    continue
                kind = "texturedir" if element.tag == "texture" else "meshdir" if element.tag in MESH_LIKE else ""
                subs = {""} | dirs["assetdir"] | (dirs[kind] if kind else set())
                for place in _inside(folder, value, [b / s for b in bases for s in subs],
                                     f"<{element.tag} {key}> of {file.name}"):
                    total += _regular(place, f"<{element.tag} {key}> of {file.name}:")
                    if place.is_file() and place not in out:
                        out.append(place)
    if total > MAX_ROBOT_BYTES:
        raise MjcfFileError(f"the robot's files are {total / 1e6:.0f} MB together, more than the limit of "
                            f"{MAX_ROBOT_BYTES / 1e6:.0f} MB (they are read to be hashed); simplify its meshes")
    return out


def _xml_files(main: Path, folder: Path) -> tuple[dict, dict, int]:
    """({each XML file: its parsed tree}, the compiler folders named in any of them, their bytes):
    the main file and its includes, recursively, each checked (``robot_files``)."""
    trees: dict[Path, ET.ElementTree] = {}
    dirs: dict[str, set[str]] = {"assetdir": set(), "meshdir": set(), "texturedir": set()}
    todo, total = [(main, "robot.body.file")], 0
    while todo:
        file, what = todo.pop(0)
        if file in trees:
            continue
        if len(trees) >= MAX_XML_FILES:
            raise MjcfFileError(f"{main.name} includes more than {MAX_XML_FILES} files")
        size = _regular(file, what)
        total += size
        if not file.exists():
            continue
        if total > MAX_ROBOT_BYTES:
            raise MjcfFileError(f"{file.name} makes the robot's files more than {MAX_ROBOT_BYTES / 1e6:.0f} MB")
        try:
            trees[file] = tree = ET.parse(file)
        except ET.ParseError:
            continue                       # MuJoCo's own message says what is wrong with it
        for compiler in tree.iter("compiler"):
            for key in dirs:
                if key in compiler.attrib:
                    _inside(folder, compiler.attrib[key].rstrip("/\\") or ".", [main.parent],
                            f"<compiler {key}> of {file.name}")
                    dirs[key].add(compiler.attrib[key])
        bases = [main.parent] + ([file.parent] if file.parent != main.parent else [])
        for include in tree.iter("include"):
            for place in _inside(folder, include.attrib.get("file", ""), bases, f"<include file> of {file.name}"):
                todo.append((place, f"<include file> of {file.name}:"))
    return trees, dirs, total


def robot_digest(path: Path, folder: Path) -> str:
    """A hash of the robot's content: the bytes of the MJCF file and of every file MuJoCo may open
    for it (``robot_files``), with their paths relative to it; a file alone hashes as its bytes (as
    before includes and assets were hashed), so moving a robot's folder keeps its hash."""
    import hashlib
    import os

    files = robot_files(path, folder)
    main = files[0]
    digest = hashlib.sha256(main.read_bytes())
    for file in sorted(files[1:], key=lambda f: os.path.relpath(f, main.parent)):
        digest.update(b"\0" + os.path.relpath(file, main.parent).encode() + b"\0")
        digest.update(file.read_bytes())
    return digest.hexdigest()[:16]
