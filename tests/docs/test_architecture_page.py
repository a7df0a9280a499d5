"""docs/architecture.md shows today's house (issue 33): its module list names every subpackage and
module of pytest_navscenario and nothing that is gone, and its "imports from" table is what the code
imports. Add, move or remove a module and this fails until the page follows."""
from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "pytest_navscenario"
PAGE = ROOT / "docs" / "architecture.md"


def _section(name: str) -> str:
    text = PAGE.read_text(encoding="utf-8")
    start, end = f"<!-- section:{name} -->", f"<!-- /section:{name} -->"
    assert start in text and end in text, f"docs/architecture.md lost its {start} ... {end} markers"
    return text[text.index(start) + len(start):text.index(end)]


def _packages() -> dict[str, set[str]]:
    """Subpackage (as the page writes it: 'sim/', 'sim/bodies/', 'pytest_navscenario/') -> its modules."""
    out = {}
    for init in sorted(PACKAGE.rglob("__init__.py")):
        folder = init.parent
        rel = folder.relative_to(PACKAGE).as_posix()
        key = "pytest_navscenario/" if rel == "." else rel + "/"
        out[key] = {p.name for p in folder.glob("*.py") if p.name != "__init__.py"}
    return out


def _listed() -> dict[str, set[str]]:
    """The page's module list: each bullet's subpackage -> the module names it gives."""
    items = re.split(r"\n- ", "\n" + _section("modules").strip())
    out = {}
    for item in filter(None, (i.strip() for i in items)):
        head = re.match(r"`([\w/]+/)`", item)
        assert head, f"a bullet of the module list does not start with a `subpackage/`: {item[:60]!r}"
        out[head.group(1)] = set(re.findall(r"`(\w+\.py)`", item[head.end():])) - {"__init__.py"}
    return out


def test_every_subpackage_and_module_is_on_the_architecture_page():
    have, listed = _packages(), _listed()
    problems = [f"subpackage {pkg} has no bullet" for pkg in have if pkg not in listed]
    problems += [f"{pkg}: the bullet names no longer existing subpackage" for pkg in listed if pkg not in have]
    for pkg, modules in have.items():
        if pkg in listed:
            problems += [f"{pkg}{m} is not named" for m in sorted(modules - listed[pkg])]
            problems += [f"{pkg}{m} is named but does not exist" for m in sorted(listed[pkg] - modules)]
    assert not problems, ("docs/architecture.md, section 'Every module', is out of date (add the module to its "
                          "subpackage's bullet, and to the layer table or a section if it is one to read first):\n  "
                          + "\n  ".join(problems))


def _layer_of(module: Path, node: ast.ImportFrom | ast.Import) -> list[str]:
    """The top-level subpackages of pytest_navscenario an import statement in ``module`` names."""
    parts = module.relative_to(PACKAGE).with_suffix("").parts
    if isinstance(node, ast.Import):
        names = [a.name for a in node.names]
    elif node.level:
        base = list(parts[:-1])                   # the module's package
        base = base[:len(base) - (node.level - 1)] if node.level > 1 else base
        if node.level - 1 > len(parts) - 1:
            return []
        names = [".".join(["pytest_navscenario", *base, *(node.module.split(".") if node.module else [])])]
        if not node.module:                       # from .. import x, y: the names are modules or attributes
            names = [n + "." + a.name for n in names for a in node.names]
    else:
        names = [node.module or ""]
    out = []
    for name in names:
        bits = name.split(".")
        if bits[0] == "pytest_navscenario" and len(bits) > 1:
            out.append(bits[1])
    return out


def test_the_imports_from_table_is_what_the_code_imports():
    layers = {d.name for d in PACKAGE.iterdir() if (d / "__init__.py").exists()}
    real: dict[str, set[str]] = {layer: set() for layer in layers}
    for module in PACKAGE.rglob("*.py"):
        rel = module.relative_to(PACKAGE).parts
        if len(rel) < 2 or rel[0] not in layers:
            continue
        for node in ast.walk(ast.parse(module.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                real[rel[0]] |= {t for t in _layer_of(module, node) if t in layers and t != rel[0]}
    page = {}
    for row in _section("uses").strip().splitlines()[2:]:
        cells = [c.strip() for c in row.strip("|").split("|")]
        page[cells[0].strip("`/")] = {c.strip() for c in cells[1].split(",") if c.strip()}
    assert page == real, "docs/architecture.md's 'imports from' table differs from the code: " + "; ".join(
        f"{layer}/: page {sorted(page.get(layer, set()))}, code {sorted(real.get(layer, set()))}"
        for layer in sorted(set(page) | set(real)) if page.get(layer) != real.get(layer))
