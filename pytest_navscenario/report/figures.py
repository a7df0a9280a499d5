"""Figure plumbing shared by every picture: an Agg figure without pyplot, mathtext off for the
user's names, PNG bytes and atomic PNG files. matplotlib is imported inside the functions."""
from __future__ import annotations

import functools
import io
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure


def as_written(build: Callable[..., "Figure"]) -> Callable[..., "Figure"]:
    """Build the figure with matplotlib's mathtext off: the names it shows are the user's, drawn as
    written ('$' in an obstacle's name started mathtext: 'x$\\frac{$y' made the plot fail, 'cost $5
    and $x' lost its dollars). matplotlib's rcParams are left as they were."""
    @functools.wraps(build)
    def wrapper(*args: Any, **kwargs: Any) -> "Figure":
        import matplotlib

        with matplotlib.rc_context({"text.parse_math": False}):
            return build(*args, **kwargs)
    return wrapper


def _figure(width: float, height: float, constrained: bool = True) -> "Figure":
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=100, layout="constrained" if constrained else None)
    FigureCanvasAgg(fig)
    return fig


def png_bytes(fig: "Figure", dpi: int = 100) -> bytes:
    """The figure as PNG bytes (for embedding in HTML)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


def save_figure(fig: "Figure", path: str | os.PathLike, dpi: int = 100) -> Path:
    """Write the figure as PNG atomically (a temporary file, then a rename); return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_bytes(png_bytes(fig, dpi))
    os.replace(tmp, path)
    return path
