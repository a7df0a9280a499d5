"""The files an MJCF robot is made of: the file itself and those it names (meshes, textures,
heightfields, skins, included files, recursively), found by reading its XML (no MuJoCo), so that a
frozen failure can carry its robot beside it.

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
