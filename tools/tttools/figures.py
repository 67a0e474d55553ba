"""Saving a chart one way: save(fig, path) lays the figure out, makes the folder and writes
the file atomically (a temporary beside it, then renamed), so a reader or a killed run never
leaves half a PNG; the format follows the file name."""
import os


def save(fig, path, dpi=None):
    """Writes the matplotlib figure `fig` to `path`; returns `path`."""
    fig.tight_layout()
    folder = os.path.dirname(path) or "."
    os.makedirs(folder, exist_ok=True)
    fmt = os.path.splitext(path)[1][1:].lower() or "png"
    tmp = os.path.join(folder, f".{os.path.basename(path)}.tmp-{os.getpid()}")
    try:
        fig.savefig(tmp, format=fmt, dpi=dpi if dpi is not None else "figure")
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    return path
