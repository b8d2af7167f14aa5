"""Matplotlib figures: meshes, deformed shapes coloured by a field, beam set-ups.

matplotlib is imported on first use; figures are drawn with the non-interactive
Agg backend when no display backend has been chosen.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .mesh import Mesh

__all__ = [
    "pyplot",
    "figure",
    "draw_mesh",
    "draw_deformed",
    "draw_interfaces",
    "interface_edges",
    "draw_beam_setup",
    "save",
]


def pyplot():
    """matplotlib.pyplot, with the Agg backend when no display backend was chosen."""
    import matplotlib

    if matplotlib.get_backend().lower() not in ("agg", "pdf", "svg", "ps", "cairo"):
        try:
            matplotlib.use("Agg")
        except Exception:  # pragma: no cover - backend already fixed by the user
            pass
    import matplotlib.pyplot as plt

    return plt


def figure(ncols: int = 1, nrows: int = 1, size: tuple[float, float] = (8.0, 4.0)):
    """A new figure and its axes."""
    plt = pyplot()
    return plt.subplots(nrows, ncols, figsize=size, squeeze=False)


def draw_mesh(ax, mesh: Mesh, points: np.ndarray | None = None, **kw):
    """Draw the bonds of ``mesh`` (optionally at displaced ``points``, shape (N, 2))."""
    from matplotlib.collections import LineCollection

    p = mesh.points if points is None else points
    b = mesh.topology.bonds
    if mesh.is_periodic:
        keep = np.all(mesh.topology.bond_image == 0, axis=1)
        b = b[keep]
    segs = np.stack([p[b[:, 0]], p[b[:, 1]]], axis=1)
    style = {"colors": "k", "linewidths": 0.3}
    style.update(kw)
    ax.add_collection(LineCollection(segs, **style))
    ax.set_aspect("equal")
    ax.autoscale_view()
    return ax


def draw_deformed(
    ax,
    mesh: Mesh,
    u: np.ndarray,
    scale: float = 1.0,
    field: np.ndarray | None = None,
    label: str = "|u|",
    cmap: str = "viridis",
    edges: bool = True,
    shown: np.ndarray | None = None,
    shown_is: str = "the nodes shown",
):
    """Deformed mesh ``x + scale u`` coloured by a nodal ``field`` (default ``|u|``).

    The colour range is that of the nodes ``shown`` (a boolean mask, shape (N,); default
    all), clipped to the 1st-99th percentiles of the field when the extremes reach far
    beyond them (stress peaks under point loads would otherwise spend the whole range on
    a few nodes); the colour bar then says so and shows arrows.
    """
    plt = pyplot()
    u = np.asarray(u, dtype=float).reshape(-1, 2)
    p = mesh.points + scale * u
    f = np.hypot(u[:, 0], u[:, 1]) if field is None else np.asarray(field, dtype=float)
    vmin, vmax, extend = robust_range(f if shown is None or not shown.any() else f[shown])
    clipped = extend != "neither"
    below, above = bool(f.min() < vmin), bool(f.max() > vmax)
    extend = {(False, False): "neither", (True, False): "min", (False, True): "max"}.get(
        (below, above), "both"
    )
    tpc = ax.tripcolor(
        p[:, 0], p[:, 1], mesh.triangles, f, shading="gouraud", cmap=cmap, vmin=vmin, vmax=vmax
    )
    if edges and mesh.n_points <= 20000:
        draw_mesh(ax, mesh, p, colors="k", linewidths=0.15, alpha=0.5)
    if clipped:
        label += " (colours clipped to the 1-99 % percentiles)"
    elif extend != "neither":
        label += f" (range of {shown_is})"
    plt.colorbar(tpc, ax=ax, label=label, shrink=0.8, extend=extend)
    ax.set_aspect("equal")
    return ax


def interface_edges(mesh: Mesh, tri_material: np.ndarray) -> np.ndarray:
    """Edges shared by two triangles of different materials, shape (k, 2) node pairs."""
    t = mesh.triangles
    e = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    owner = np.tile(np.arange(len(t)), 3)
    order = np.lexsort((e[:, 1], e[:, 0]))
    e, owner = e[order], owner[order]
    same = np.all(e[1:] == e[:-1], axis=1)
    mat = np.asarray(tri_material)
    cut = same & (mat[owner[1:]] != mat[owner[:-1]])
    return e[1:][cut]


def draw_interfaces(ax, mesh: Mesh, tri_material: np.ndarray, points: np.ndarray | None = None):
    """Draw the material interfaces (edges between triangles of different materials)."""
    from matplotlib.collections import LineCollection

    edges = interface_edges(mesh, tri_material)
    if len(edges):
        p = mesh.points if points is None else points
        segs = np.stack([p[edges[:, 0]], p[edges[:, 1]]], axis=1)
        ax.add_collection(LineCollection(segs, colors="w", linewidths=1.6))
        ax.add_collection(LineCollection(segs, colors="k", linewidths=0.8))
    return ax


def robust_range(f: np.ndarray, spread: float = 3.0) -> tuple[float, float, str]:
    """Colour limits of a field: its 1st and 99th percentiles where the minimum or
    maximum lies more than ``spread - 1`` times that span beyond them, else the extremes.

    Returns ``(vmin, vmax, extend)`` with ``extend`` for the colour bar.
    """
    lo, hi = float(np.min(f)), float(np.max(f))
    p1, p99 = (float(v) for v in np.percentile(f, [1.0, 99.0]))
    span = max(p99 - p1, 1e-300)
    cut_lo = p1 - lo > (spread - 1.0) * span
    cut_hi = hi - p99 > (spread - 1.0) * span
    extend = {(False, False): "neither", (True, False): "min", (False, True): "max"}.get(
        (cut_lo, cut_hi), "both"
    )
    return (p1 if cut_lo else lo), (p99 if cut_hi else hi), extend


def draw_beam_setup(ax, length: float, height: float, body_force: float = -1.0):
    """Sketch of a beam clamped at both ends under its own weight."""
    from matplotlib.patches import Rectangle

    ax.add_patch(Rectangle((0, 0), length, height, fill=True, fc="#dde6f2", ec="k", lw=1.5))
    hatch_w = 0.08 * height
    for x0 in (-hatch_w, length):
        ax.add_patch(
            Rectangle(
                (x0, -0.15 * height),
                hatch_w,
                1.3 * height,
                fill=False,
                hatch="////",
                ec="k",
                lw=0.8,
            )
        )
    xs = np.linspace(0.1 * length, 0.9 * length, 9)
    ys = np.full_like(xs, 0.7 * height)
    ax.quiver(
        xs,
        ys,
        np.zeros_like(xs),
        np.sign(body_force) * np.ones_like(xs),
        angles="xy",
        scale_units="xy",
        scale=1 / (0.35 * height),
        color="tab:red",
        width=0.004,
    )
    ax.text(
        0.5 * length,
        0.85 * height,
        f"body force b = ({0:g}, {body_force:g}) per area",
        ha="center",
        color="tab:red",
    )
    ax.text(-0.6 * hatch_w, 1.2 * height, "clamped", ha="center")
    ax.text(length + 0.6 * hatch_w, 1.2 * height, "clamped", ha="center")
    ax.annotate(
        "", xy=(length, -0.3 * height), xytext=(0, -0.3 * height), arrowprops={"arrowstyle": "<->"}
    )
    ax.text(0.5 * length, -0.42 * height, f"L = {length:g}", ha="center")
    ax.annotate(
        "",
        xy=(length + 0.25 * height, height),
        xytext=(length + 0.25 * height, 0),
        arrowprops={"arrowstyle": "<->"},
    )
    ax.text(length + 0.3 * height, 0.5 * height, f"H = {height:g}", va="center")
    ax.set_xlim(-0.3 * height, length + 0.6 * height)
    ax.set_ylim(-0.6 * height, 1.4 * height)
    ax.set_aspect("equal")
    ax.axis("off")
    return ax


def save(fig, path: str | Path, dpi: int = 120) -> Path:
    """Save a figure (written to a temporary name, then renamed) and close it."""
    plt = pyplot()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.stem + ".tmp" + path.suffix)
    fig.tight_layout()
    fig.savefig(tmp, dpi=dpi)
    plt.close(fig)
    tmp.replace(path)
    return path
