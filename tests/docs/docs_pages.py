"""Executable docs pages: read the commands, files and outputs a page shows, run them in a fresh
folder, compare what the run printed with what the page shows, and rewrite the page's outputs from
a real run (update mode).

The markup is an HTML comment on the line before a fenced block (blank lines between are allowed);
GitHub and MkDocs render nothing for it. docs/contributing.md is the user-facing description.

    <!-- run -->                  run the block: a ``console`` block's ``$ `` lines (the lines after
                                  each are its output, checked when present), an ``sh``/``bash``
                                  block's lines, or a ``python`` block (fed to ``python -``)
    <!-- run: exit 1 -->          the same; the last command exits 1, the others 0 (default: all 0)
    <!-- run: exit 0 1 1 -->      the same, with each command's exit status in order
    <!-- output -->               the output of the last command run (a ``text`` block)
    <!-- file: PATH -->           write the block to PATH (relative to the current folder)
    <!-- append: PATH -->         append the block to PATH (after two blank lines)
    <!-- skip: REASON -->         a command block that is not run; the docs test reports it as
                                  skipped with REASON

In an output, a line ``...`` stands for any number of lines (none included). Before comparing,
both sides go through ``MASKS`` (wall times, memory addresses) and the run's temporary folder is
shown as ``~``; lines that describe the machine (``LEFT_OUT``) are dropped from the run's output.
``pip install`` commands are not run: the docs test runs the package installed as it is.
"""
from __future__ import annotations

import difflib
import os
import re
import resource
import shlex
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from pytest_navscenario.core.files import atomic_write_text

MARKER = re.compile(r"^\s*<!--\s*(run|output|file|append|skip)\b\s*(?::\s*(.*?))?\s*-->\s*$")
FENCE = re.compile(r"^(\s*)(`{3,}|~{3,})\s*([\w+-]*)(.*)$")
SHELL = {"sh", "bash", "shell", "console"}
#: pytest's section rules: a title centred in '=' or '_', the rule's length following the title's
RULE = re.compile(r"^([=_])\1* (.+?) \1+$")     # a long title gets a fill of one

#: (name, pattern, replacement): the values a run may print differently each time, shown as named
#: placeholders on both sides of the comparison. docs/contributing.md lists them for page writers.
MASKS: list[tuple[str, re.Pattern, str]] = [
    ("pytest's session time", re.compile(r"\bin \d+(?:\.\d+)?s(?: \(\d+:\d\d:\d\d\))?"), "in <wall-time>"),
    ("a search's wall time, ending its summary line", re.compile(r", \d+(?:\.\d+)? s$"), ", <wall-time>"),
    ("wall time of a run", re.compile(r"\bwall time: \d+(?:\.\d+)? m?s\b"), "wall time: <wall-time>"),
    ("tick times of check-planner", re.compile(r"\b(median|max) \d+(?:\.\d+)? ms\b"), r"\1 <tick-time>"),
    ("memory addresses", re.compile(r"\b0x[0-9a-fA-F]{6,}\b"), "0x<address>"),
    ("pytest's rule lines", RULE, r"\1\1\1 \2 \1\1\1"),
]

#: Lines of a run's output that describe the machine (Python, installed plugins), not the tool.
LEFT_OUT = re.compile(r"^(platform |plugins: |benchmark: |cachedir: |hypothesis profile |"
                      r"Using --randomly-seed)")

ELLIPSIS = "..."


class MarkupError(ValueError):
    """A page's markup is wrong: says the page, the line and how to fix it."""


@dataclass
class Block:
    """A fenced code block: where it is on the page and what it holds."""
    page: Path
    fence_line: int                  # 0-based index of the opening fence
    lang: str
    lines: list[str]                 # the content, without the fences
    marker: str | None = None        # run, output, file, append, skip
    argument: str = ""

    @property
    def where(self) -> str:
        return f"{self.page.name}:{self.fence_line + 1}"

    def content_line(self, i: int) -> int:
        """The page's 0-based line index of content line ``i``."""
        return self.fence_line + 1 + i


@dataclass
class Command:
    """One command to run, with the exit status and the output the page expects."""
    text: str
    block: Block
    exit: int = 0
    output: list[str] | None = None  # the expected output's lines, or None when the page shows none
    output_block: Block | None = None
    output_start: int = 0            # index of the output's first line in output_block.lines
    python: bool = False


@dataclass
class Step:
    kind: str                        # file, append, run, skip
    block: Block
    path: str = ""
    commands: list[Command] = field(default_factory=list)
    reason: str = ""


def read_blocks(page: Path) -> list[Block]:
    """Every fenced block of a page, with the marker comment before it (if any)."""
    lines = page.read_text(encoding="utf-8").splitlines()
    blocks: list[Block] = []
    pending: tuple[str, str, int] | None = None
    i = 0
    while i < len(lines):
        line = lines[i]
        marker = MARKER.match(line)
        fence = FENCE.match(line)
        if marker:
            if pending:
                raise MarkupError(f"{page.name}:{pending[2] + 1}: marker '<!-- {pending[0]} -->' is followed by "
                                  f"another marker, not by a code block (fix: one marker per block)")
            pending = (marker.group(1), (marker.group(2) or "").strip(), i)
        elif fence:
            indent, ticks, lang = fence.group(1), fence.group(2), fence.group(3).lower()
            end = i + 1
            while end < len(lines) and not re.match(rf"^{re.escape(indent)}{ticks[0]}{{{len(ticks)},}}\s*$", lines[end]):
                end += 1
            if end == len(lines):
                raise MarkupError(f"{page.name}:{i + 1}: code block never closed")
            content = [ln[len(indent):] if ln.startswith(indent) else ln.lstrip() for ln in lines[i + 1:end]]
            block = Block(page, i, lang, content)
            if pending:
                block.marker, block.argument = pending[0], pending[1]
                pending = None
            blocks.append(block)
            i = end
        elif pending and line.strip():
            raise MarkupError(f"{page.name}:{pending[2] + 1}: marker '<!-- {pending[0]} -->' must come right before "
                              f"a code block (blank lines only between), found text at line {i + 1}")
        i += 1
    if pending:
        raise MarkupError(f"{page.name}:{pending[2] + 1}: marker '<!-- {pending[0]} -->' at the end of the page "
                          f"has no code block after it")
    return blocks


def unmarked_shell_blocks(page: Path) -> list[str]:
    """Shell blocks with neither ``run`` nor ``skip``: every command a page shows must say which."""
    return [b.where for b in read_blocks(page) if b.lang in SHELL and b.marker not in ("run", "skip")]


def _logical_lines(lines: list[str]) -> list[tuple[int, str]]:
    """(index of first line, command) with backslash continuations joined."""
    out, buf, start = [], [], 0
    for i, line in enumerate(lines):
        if not buf:
            start = i
        buf.append(line.rstrip())
        if line.rstrip().endswith("\\"):
            buf[-1] = buf[-1][:-1]
            continue
        out.append((start, " ".join(part.strip() for part in buf).strip()))
        buf = []
    if buf:
        out.append((start, " ".join(part.strip() for part in buf).strip()))
    return out


def _exits(block: Block, count: int) -> list[int]:
    argument = block.argument
    if not argument:
        return [0] * count
    m = re.fullmatch(r"exit((?:\s+\d+)+)", argument)
    if not m:
        raise MarkupError(f"{block.where}: '<!-- run: {argument} -->' is not understood "
                          f"(fix: '<!-- run -->' or '<!-- run: exit N ... -->', one status per command)")
    statuses = [int(s) for s in m.group(1).split()]
    if len(statuses) == 1:
        return [0] * (count - 1) + statuses      # one status: the last command's, the others exit 0
    if len(statuses) != count:
        raise MarkupError(f"{block.where}: '<!-- run: {argument} -->' gives {len(statuses)} exit status(es) for "
                          f"{count} command(s) (fix: one per command, in order, or one for the last command)")
    return statuses


def read_steps(page: Path) -> list[Step]:
    """What a page asks the reader to do, in order."""
    steps: list[Step] = []
    last: Command | None = None
    for block in read_blocks(page):
        kind = block.marker
        if kind in ("file", "append"):
            if not block.argument:
                raise MarkupError(f"{block.where}: '<!-- {kind}: PATH -->' needs the path")
            steps.append(Step(kind, block, path=block.argument))
        elif kind == "skip":
            if not block.argument:
                raise MarkupError(f"{block.where}: '<!-- skip: REASON -->' needs the reason shown in the test report")
            steps.append(Step("skip", block, reason=block.argument))
            last = None
        elif kind == "output":
            if last is None or last.output is not None:
                raise MarkupError(f"{block.where}: '<!-- output -->' must follow a run block whose last command "
                                  f"shows no output of its own")
            last.output, last.output_block, last.output_start = list(block.lines), block, 0
        elif kind == "run":
            commands = _commands(block)
            for command, status in zip(commands, _exits(block, len(commands))):
                command.exit = status
            steps.append(Step("run", block, commands=commands))
            last = commands[-1] if commands else None
    return steps


def _commands(block: Block) -> list[Command]:
    if block.lang == "python":
        return [Command("\n".join(block.lines), block, python=True)]
    if block.lang == "console":
        commands: list[Command] = []
        i = 0
        while i < len(block.lines):
            line = block.lines[i]
            if not line.startswith("$ "):
                raise MarkupError(f"{block.where}: line {i + 1} of the console block is neither a '$ ' command "
                                  f"nor its output")
            text = line[2:]
            while text.endswith("\\") and i + 1 < len(block.lines):
                i += 1
                text = text[:-1].rstrip() + " " + block.lines[i].strip()
            j = i + 1
            while j < len(block.lines) and not block.lines[j].startswith("$ "):
                j += 1
            output = block.lines[i + 1:j]
            while output and not output[-1].strip():
                output.pop()
            cmd = Command(text.strip(), block)
            if output:
                cmd.output, cmd.output_block, cmd.output_start = output, block, i + 1
            commands.append(cmd)
            i = j
        return commands
    if block.lang in SHELL:
        return [Command(text, block) for _, text in _logical_lines(block.lines)
                if text and not text.startswith("#")]
    raise MarkupError(f"{block.where}: '<!-- run -->' on a '{block.lang or 'plain'}' block "
                      f"(fix: run console, sh, bash or python blocks)")


# ---------------------------------------------------------------------------------------------
# comparing outputs


def _rule(char: str, title: str, width: int = 80) -> str:
    """A pytest section rule, as pytest's terminal writer centres it (``sep``)."""
    fill = char * max((width - len(title) - 2) // 2, 1)
    line = f"{fill} {title} {fill}"
    return line + char if len(line) + 1 <= width else line


def shown(text: str, home: Path) -> list[str]:
    """A run's output as a page would show it: the temporary folder as ``~`` (a pytest rule with
    the folder in its title centred again), machine lines out."""
    variants = sorted({str(home.resolve()), str(home)}, key=len, reverse=True)
    lines = []
    for line in text.splitlines():
        if LEFT_OUT.match(line):
            continue
        if any(v in line for v in variants):
            for v in variants:
                line = line.replace(v, "~")
            rule = RULE.match(line)
            if rule:
                line = _rule(rule.group(1), rule.group(2))
        lines.append(line.rstrip())
    while lines and not lines[-1]:
        lines.pop()
    return lines


def masked(line: str) -> str:
    for _, pattern, replacement in MASKS:
        line = pattern.sub(replacement, line)
    return line.rstrip()


def matches(expected: list[str], actual: list[str]) -> bool:
    """Whether ``actual`` is ``expected`` with each ``...`` line standing for any lines."""
    exp = [masked(e) for e in expected]
    act = [masked(a) for a in actual]
    # reachable[j]: expected[:i] can match actual[:j]
    reachable = [True] + [False] * len(act)
    for e in exp:
        if e.strip() == ELLIPSIS:
            for j in range(1, len(act) + 1):
                reachable[j] = reachable[j] or reachable[j - 1]
        else:
            reachable = [False] + [reachable[j - 1] and act[j - 1] == e for j in range(1, len(act) + 1)]
    return reachable[-1]


def _shape(line: str) -> str:
    return re.sub(r"[0-9a-f]{6,}|\d+(\.\d+)?", "#", masked(line))


def _similarity(a: str, b: str) -> float:
    if a == b:
        return 2.0
    sa, sb = _shape(a), _shape(b)
    if sa == sb:
        return 1.5
    return difflib.SequenceMatcher(None, sa, sb, autojunk=False).ratio()


def updated(expected: list[str], actual: list[str]) -> list[str]:
    """The page's output block rewritten from a run: the same ``...`` lines, each stretch of lines
    the page shows replaced by the stretch of the run's output most like it (see _best_span). A
    stretch at the start or the end of the block stays there. A block without ``...`` becomes the
    whole output."""
    if not any(e.strip() == ELLIPSIS for e in expected):
        return list(actual)
    segments: list[list[str]] = [[]]
    for e in expected:
        if e.strip() == ELLIPSIS:
            segments.append([])
        else:
            segments[-1].append(e)
    out: list[str] = []
    pos = 0
    for k, segment in enumerate(segments):
        if k:
            out.append(ELLIPSIS)
        if not segment:
            continue
        first_anchored = k == 0
        last_anchored = k == len(segments) - 1
        span = _best_span(segment, actual, pos, first_anchored, last_anchored)
        out.extend(actual[span[0]:span[1]])
        pos = span[1]
    return out


def _best_span(segment: list[str], actual: list[str], pos: int, at_start: bool, at_end: bool) -> tuple[int, int]:
    """(start, end) of the run's lines to show for ``segment``, searched from ``pos``: a stretch that
    ends the block runs to the end of the output from the line most like its first (so a list that
    grew shows whole); any other keeps its length (a sample of the output, as the page chose)."""
    n, size = len(segment), len(actual)
    if pos >= size:
        return size, size
    starts = [0] if at_start else range(pos, size)
    if at_end:
        best = max(starts, key=lambda s: (_similarity(segment[0], actual[s]) - 0.02 * abs((size - s) - n), -s))
        return best, size
    starts = [s for s in starts if s + n <= size] or [max(pos, size - n)]
    best = max(starts, key=lambda s: (sum(_similarity(x, a) for x, a in zip(segment, actual[s:s + n])), -s))
    return best, min(size, best + n)


# ---------------------------------------------------------------------------------------------
# running


def command_env() -> dict[str, str]:
    """The environment of a page's commands: this one, without what pytest and xdist set for
    themselves (an inner pytest must not think it is a worker), 80 columns, no colours."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTEST_", "PYTEST_XDIST"))}
    env.pop("COLUMNS", None)
    # pytest prints whole short-summary lines when it sees a CI variable and cuts them to the
    # terminal's width otherwise: the pages show a reader's terminal, so CI's runs must too.
    for name in ("CI", "BUILD_NUMBER"):
        env.pop(name, None)
    env.update(COLUMNS="80", LINES="24", PY_COLORS="0", NO_COLOR="1", TERM="dumb")
    return env


@dataclass
class Ran:
    command: Command
    status: int
    output: list[str]                # as shown: see shown()
    wall: float = 0.0                # seconds
    cpu: float = 0.0                 # seconds of CPU of the command and everything it started


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def without_pip_install(text: str) -> str:
    """The command with its ``pip install`` parts left out (the package is installed as it is)."""
    parts = [p.strip() for p in text.split("&&")]
    kept = [p for p in parts if not re.match(r"^(python3? -m )?pip3? install\b", p)]
    return " && ".join(kept)


def run(command: Command, cwd: Path, home: Path, timeout: float = 600) -> tuple[Ran, Path]:
    """Run one command in ``cwd``; return what it did and the folder it ended in (``cd``)."""
    env = command_env()
    # ``python``, ``pytest`` and ``navscenario`` as a user types them: this interpreter's first
    env["PATH"] = str(Path(sys.executable).parent) + os.pathsep + env.get("PATH", "")
    where = home / ".docs-cwd"
    if command.python:
        argv, stdin = [sys.executable, "-"], command.text
    else:
        text = without_pip_install(command.text)
        if not text:
            return Ran(command, 0, []), cwd
        argv, stdin = ["bash", "-c", f"{text}\n__status=$?\npwd > {shlex.quote(str(where))}\nexit $__status\n"], None
        where.unlink(missing_ok=True)
    wall, cpu = time.perf_counter(), _children_cpu()
    proc = subprocess.run(argv, input=stdin, cwd=cwd, env=env, text=True,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=timeout)
    ran = Ran(command, proc.returncode, shown(proc.stdout, home), time.perf_counter() - wall, _children_cpu() - cpu)
    new_cwd = Path(where.read_text().strip()) if not command.python and where.exists() else cwd
    return ran, new_cwd


@dataclass
class PageRun:
    """What running pages found: problems (page:line: what), skipped blocks, rewrites to make."""
    problems: list[str] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)
    rewrites: dict[Path, list[tuple[int, int, list[str]]]] = field(default_factory=dict)
    ran: list[Ran] = field(default_factory=list)


def run_pages(pages: list[Path], home: Path, cwd: Path, update: bool) -> PageRun:
    """Run the pages' steps in order, in one folder that carries over from page to page."""
    result = PageRun()
    for page in pages:
        for step in read_steps(page):
            if step.kind in ("file", "append"):
                target = cwd / step.path
                target.parent.mkdir(parents=True, exist_ok=True)
                text = "\n".join(step.block.lines) + "\n"
                if step.kind == "append" and target.exists():      # two blank lines between, as PEP 8 has it
                    text = target.read_text(encoding="utf-8").rstrip("\n") + "\n\n\n" + text
                target.write_text(text, encoding="utf-8")
            elif step.kind == "skip":
                result.skipped.append(f"{step.block.where}: {step.reason}")
            else:
                for command in step.commands:
                    ran, cwd = run(command, cwd, home)
                    result.ran.append(ran)
                    _check(ran, result, update)
    return result


def _check(ran: Ran, result: PageRun, update: bool) -> None:
    command = ran.command
    where = command.block.where
    label = command.text.splitlines()[0] if command.python else command.text
    if ran.status != command.exit:
        tail = "\n".join(ran.output[-30:])
        result.problems.append(f"{where}: `{label}` exited {ran.status}, the page says {command.exit}; "
                               f"its output ended:\n{tail}")
    if command.output is None:
        return
    if matches(command.output, ran.output):
        return
    proposal = updated(command.output, ran.output)
    block = command.output_block
    if update:
        first = block.content_line(command.output_start)
        result.rewrites.setdefault(block.page, []).append((first, first + len(command.output), proposal))
        return
    diff = "\n".join(difflib.unified_diff(command.output, proposal, "the page", "a run", lineterm="", n=1))
    result.problems.append(f"{block.where}: the output of `{label}` differs from a run "
                           f"(NAVSCENARIO_DOCS_UPDATE=1 rewrites it):\n{diff}")


def apply_rewrites(rewrites: dict[Path, list[tuple[int, int, list[str]]]]) -> list[str]:
    """Write the new outputs into the pages (bottom up, so line numbers hold); return what changed."""
    changed = []
    for page, edits in rewrites.items():
        lines = page.read_text(encoding="utf-8").splitlines()
        for start, end, new in sorted(edits, reverse=True):
            lines[start:end] = new
            changed.append(f"{page.name}:{start + 1}")
        atomic_write_text(page, "\n".join(lines) + "\n")
    return changed
