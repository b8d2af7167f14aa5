"""Pictures (PNG, written atomically): the deformed body coloured by a field, the load-
displacement curve and the crack pattern of a fracture analysis, and the framing that
picks the region a picture shows. matplotlib is imported on first use
(:mod:`dvstatic.plot`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._atomic import atomic_path, finish
from .errors import InputError
from .report import nodal_field

__all__ = [
    "default_scale",
    "picture_view",
    "near_point_loads",
    "figure_size",
    "write_png",
    "write_fracture_curve",
    "crack_faces",
    "write_crack_png",
    "SMALL_PART",
    "POINT_LOAD_SPACINGS",
]


def default_scale(solution, view=None) -> float:
    """Displacement magnification of pictures: the largest displacement drawn as 10 %
    of the body's size, or, in a ``view`` (x0, x1, y0, y1) that frames a part of the
    body, the largest displacement in it as 10 % of the part (a fifth of the view); 1 for
    nonlinear solutions, and where nothing moves."""
    x = solution.model.mesh.points
    u = np.hypot(*np.asarray(solution.u).reshape(-1, 2).T)
    size = float(np.max(np.ptp(x, axis=0)))
    if view is not None:
        inside = _inside(x, view)
        if inside.any() and not inside.all():  # a framed part: 10 % of the part's size
            size, u = 0.2 * max(view[1] - view[0], view[3] - view[2]), u[inside]
    umax = float(u.max()) if len(u) else 0.0
    return 1.0 if solution.info.nonlinear or umax == 0 else 0.1 * size / umax


#: a hole, loaded part or crack is framed by the default picture (two of its sizes around
#: it) where that frame is less than this fraction of the body's bounding box
SMALL_PART = 0.5


def picture_view(
    solution, view=None, stress: str | None = None, field: str = "|u|"
) -> tuple[float, float, float, float]:
    """The region a picture shows, (x0, x1, y0, y1) (length).

    ``view`` as given (four numbers), ``"body"`` for the whole body, or None: the holes
    (inner boundary loops), else the parts carrying surface or point loads, framed with
    two of their sizes around them where that frame is less than :data:`SMALL_PART` of
    the body's box *and* holds what the picture is about: the nodes where the coloured
    ``field`` and the von Mises stress peak (``stress``: the recovery; away from point
    loads). The whole body otherwise (a loaded end of a cantilever is small, but its
    stresses peak at the clamp).
    """
    x = solution.model.mesh.points
    lo, hi = x.min(axis=0), x.max(axis=0)
    body = (float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1]))
    if view == "body":
        return body
    if view is not None:
        v = tuple(float(c) for c in view)
        if len(v) != 4 or not (v[0] < v[1] and v[2] < v[3]) or not np.all(np.isfinite(v)):
            raise InputError(
                f"view must be (x0, x1, y0, y1) with x0 < x1, y0 < y1, got {view}", "view"
            )
        return v
    peaks = None
    for nodes in (_hole_nodes(solution.model.mesh), _surface_loaded_nodes(solution)):
        if len(nodes) == 0:
            continue
        a, b = _frame(x, x[nodes])
        if np.allclose(a, lo) and np.allclose(b, hi):
            continue
        box = (float(a[0]), float(b[0]), float(a[1]), float(b[1]))
        peaks = _peak_nodes(solution, stress, field) if peaks is None else peaks
        if _inside(x[peaks], box).all():
            return box
    return body


def _peak_nodes(solution, stress: str | None, field: str) -> np.ndarray:
    """The nodes where ``field`` and the von Mises stress peak (in magnitude), away from
    point loads."""
    away = ~near_point_loads(solution)
    out = []
    for name in dict.fromkeys((field, "von_mises")):
        f = np.abs(nodal_field(solution, name, stress))
        f[~away] = -np.inf
        out.append(int(np.argmax(f)))
    return np.array(out)


def _frame(x: np.ndarray, part: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Corners of a picture of ``part`` (points (k, 2)) in the body of points ``x``: the
    part with two of its sizes around it (within the body) where that box is less than
    :data:`SMALL_PART` of the body's area, else the body."""
    lo, hi = x.min(axis=0), x.max(axis=0)
    if len(part) == 0:
        return lo, hi
    a, b = part.min(axis=0), part.max(axis=0)
    c, half = 0.5 * (a + b), 2.5 * max(float(np.max(b - a)), 1e-3 * float(np.max(hi - lo)))
    a, b = np.maximum(c - half, lo), np.minimum(c + half, hi)
    if np.prod(b - a) < SMALL_PART * np.prod(hi - lo):
        return a, b
    return lo, hi


#: nodes within this many local spacings of a point load are left out of a picture's
#: colour range (the stress is singular there)
POINT_LOAD_SPACINGS = 6.0


def near_point_loads(solution) -> np.ndarray:
    """Nodes within :data:`POINT_LOAD_SPACINGS` local spacings (the mean bond length at
    the loaded node) of a point load, shape (N,) bool."""
    from scipy.spatial import cKDTree

    from .problem.loads import PointLoad
    from .problem.select import select_nodes
    from .stress.fit import local_spacing

    mesh = solution.model.mesh
    out = np.zeros(mesh.n_points, dtype=bool)
    nodes = [
        select_nodes(mesh, ld.nodes, "PointLoad")
        for ld in solution.loads
        if isinstance(ld, PointLoad)
    ]
    if not nodes:
        return out
    nodes = np.unique(np.concatenate(nodes))
    radius = POINT_LOAD_SPACINGS * local_spacing(mesh)[nodes]
    tree = cKDTree(mesh.points)
    for node, r in zip(nodes, radius, strict=True):
        out[tree.query_ball_point(mesh.points[node], r)] = True
    return out


def _inside(x: np.ndarray, view) -> np.ndarray:
    return (x[:, 0] >= view[0]) & (x[:, 0] <= view[1]) & (x[:, 1] >= view[2]) & (x[:, 1] <= view[3])


def _hole_nodes(mesh) -> np.ndarray:
    """Nodes of the inner boundary loops (all loops but the one that spans the most)."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    be = mesh.boundary_edges
    if mesh.is_periodic or len(be) == 0:
        return np.zeros(0, np.int64)
    n = mesh.n_points
    g = sp.coo_matrix((np.ones(len(be)), (be[:, 0], be[:, 1])), (n, n))
    _, label = connected_components(g, directed=False)
    nodes = np.unique(be)
    loops = label[nodes]
    if len(np.unique(loops)) < 2:
        return np.zeros(0, np.int64)
    x = mesh.points
    span = {k: float(np.ptp(x[nodes[loops == k]], axis=0).sum()) for k in np.unique(loops)}
    outer = max(span, key=span.get)
    return nodes[loops != outer]


def _surface_loaded_nodes(solution) -> np.ndarray:
    """Nodes that carry a traction, pressure or point load."""
    from .problem import load_vector
    from .problem.loads import BodyForce

    loads = [ld for ld in solution.loads if not isinstance(ld, BodyForce) and not callable(ld)]
    if not loads:
        return np.zeros(0, np.int64)
    f = load_vector(solution.model.mesh, loads).reshape(-1, 2)
    return np.flatnonzero(np.any(f != 0, axis=1))


def figure_size(drawn: np.ndarray) -> tuple[float, float]:
    """Figure size (inches) that frames the drawn points (shape (N, 2)) at equal axis
    scales, with room for the colour bar: at most 9 x 9, at least 3 high."""
    lo, hi = drawn.min(axis=0), drawn.max(axis=0)
    aspect = (hi[1] - lo[1]) / max(hi[0] - lo[0], 1e-300)
    width = 9.0 if aspect <= 1.0 else max(5.0, min(9.0, 8.0 / aspect + 2.0))
    return width, max(3.0, min(9.0, (width - 2.0) * aspect + 1.5))


def write_png(
    path: str | Path,
    solution,
    field: str = "|u|",
    scale: float | None = None,
    title: str | None = None,
    stress: str | None = None,
    view=None,
) -> Path:
    """Picture of the deformed mesh coloured by a nodal field, atomically.

    ``view`` is the region shown (:func:`picture_view`: default the whole body, or its
    holes or loaded parts when they are small in it; ``"body"``; or (x0, x1, y0, y1)),
    and the colour range is that of the nodes in it. ``scale`` magnifies the
    displacement (default: :func:`default_scale`, the largest displacement as 10 % of
    the body, or in a framed view as 10 % of the framed part; 1 for nonlinear
    solutions). The x label states the magnification; the colour range
    is clipped to robust percentiles where a few nodes would take all of it (the colour
    bar says so). Material interfaces are drawn as lines.

    Raises
    ------
    InputError
        ``field="szz"`` in plane stress (it is zero), or a bad ``view``.
    """
    from . import plot

    path = Path(path)
    mesh = solution.model.mesh
    if field == "szz" and solution.model.plane == "stress":
        raise InputError("szz is zero in plane stress: pick another field", "field")
    f = nodal_field(solution, field, stress)
    box = picture_view(solution, view, stress, field)
    inside = _inside(mesh.points, box)
    if not inside.any():
        raise InputError(f"view {list(box)} holds no node of the body", "view")
    if scale is None:
        scale = default_scale(solution, box)
    drawn = mesh.points + scale * solution.u
    whole = bool(inside.all())
    frame = drawn if whole else drawn[inside]
    fig, axes = plot.figure(1, 1, figure_size(frame))
    ax = axes[0, 0]
    near = near_point_loads(solution)
    shown = inside & ~near if (inside & ~near).any() else inside
    note = "the nodes in view, away from point loads" if near.any() else "the nodes in view"
    plot.draw_deformed(
        ax, mesh, solution.u, scale=scale, field=f, label=field, shown=shown, shown_is=note
    )
    plot.draw_interfaces(ax, mesh, solution.model.material_of_triangle, drawn)
    if not whole:  # the deformed shape in view, with a margin
        lo, hi = frame.min(axis=0), frame.max(axis=0)
        pad = 0.02 * (hi - lo).max()
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_title(title or f"{solution.model.kind}: {field}")
    ax.set_xlabel(f"x   (deformed shape, displacements drawn x {scale:.3g})")
    ax.set_ylabel("y")
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = atomic_path(path).with_suffix(".png")
    plot.save(fig, tmp)
    return finish(tmp, path)


def write_fracture_curve(path: str | Path, result, title: str | None = None, references=()) -> Path:
    """The load-displacement curve of a fracture analysis as a PNG, atomically.

    Every event's critical state is a dot (the saw-tooth, snap-backs as they come); the
    line is the envelope a monotonic control displacement would follow (the states
    beyond every earlier displacement); the peak is marked. ``references``: checks
    (``quantity``, ``reference``, ``name``) of ``peak_load`` or ``peak_displacement``
    drawn as dashed lines.
    """
    from . import plot

    path = Path(path)
    d, p = result.curve()
    fig, axes = plot.figure(1, 1, (7.0, 4.5))
    ax = axes[0, 0]
    ax.plot(d, p, ".", ms=2.5, color="C0", alpha=0.45, label=f"{len(d)} events")
    ahead = d >= np.maximum.accumulate(d)
    ax.plot(np.r_[0.0, d[ahead]], np.r_[0.0, p[ahead]], "-", lw=1.2, color="C0", label="envelope")
    peak = result.peak
    if peak is not None:
        ax.plot(
            [peak.control_displacement],
            [peak.load],
            "o",
            color="C3",
            label=f"peak {peak.load:.4g} at {peak.control_displacement:.4g}",
        )
    for c in references:
        if c["quantity"] == "peak_load":
            ax.axhline(
                c["reference"], ls="--", lw=0.9, color="0.3", label=f"reference: {c['name']}"
            )
        elif c["quantity"] == "peak_displacement":
            ax.axvline(
                c["reference"], ls="--", lw=0.9, color="0.3", label=f"reference: {c['name']}"
            )
    ax.legend(fontsize=8)
    what = (
        "prescribed displacement" if result.control == "displacement" else "load-point displacement"
    )
    per = "" if result.model.thickness else " per unit thickness"
    ax.set_xlabel(f"{what} (length; work-conjugate to the load)")
    ax.set_ylabel(f"load (force{per})")
    ax.set_xlim(left=0)
    ax.set_ylim(bottom=0)
    ax.set_title(
        title or f"{result.model.kind}: {len(result.events)} events, {result.message}", fontsize=9
    )
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = atomic_path(path).with_suffix(".png")
    plot.save(fig, tmp)
    return finish(tmp, path)


def crack_faces(result, bonds=None) -> tuple[np.ndarray, np.ndarray]:
    """The Voronoi faces of ``bonds`` (default: the broken bonds, in the order they
    broke): segments (k, 2, 2) between the circumcentres of a bond's two triangles (a
    boundary bond: from its triangle's circumcentre to the bond's midpoint), and the
    bonds (k,)."""
    from .crack.pieces import bond_triangles

    mesh = result.model.mesh
    bonds = np.asarray(result.broken if bonds is None else bonds, dtype=np.int64)
    tris = bond_triangles(mesh)[bonds]
    h = result.model.geometry.circumcentre
    a, b = h[tris[:, 0]], h[tris[:, 1]]
    ends = mesh.points[mesh.topology.bonds[bonds]]
    boundary = tris[:, 0] == tris[:, 1]
    b[boundary] = ends[boundary].mean(axis=1)
    return np.stack([a, b], axis=1), bonds


#: colours of the failure modes in the crack picture
_MODE_COLOURS = {
    "tension": "tab:blue",
    "shear": "tab:green",
    "crushing": "tab:red",
    "out-of-plane": "tab:purple",
}


def _break_modes(result) -> list[str]:
    """The failure mode of every broken bond (in ``result.broken``'s order): the mode of
    the event that removed it."""
    by_bond = {e.bond: e.mode for e in result.events if e.broken}
    return [by_bond.get(int(b), "tension") for b in result.broken]


def write_crack_png(path: str | Path, result, title: str | None = None) -> Path:
    """The crack pattern of a fracture analysis as a PNG, atomically: the body's
    outline, the Voronoi faces of the broken bonds coloured by the order they broke (by
    failure mode, tension / shear / crushing / out-of-plane, when faces failed other than in
    tension), those of softened (cracked, not yet broken) bonds in grey, or pale in the
    colour of their mode when faces soften in shear; a crack in a small part of the body
    is framed."""
    from matplotlib.collections import LineCollection

    from . import plot

    path = Path(path)
    mesh = result.model.mesh
    x = mesh.points
    soft = np.flatnonzero((result.stiffness > 0) & (result.stiffness < 1))
    faces, soft_faces = crack_faces(result)[0], crack_faces(result, soft)[0]
    lo, hi = _frame(x, np.concatenate([faces, soft_faces]).reshape(-1, 2))
    fig, axes = plot.figure(1, 1, figure_size(np.array([lo, hi])))
    ax = axes[0, 0]
    ax.add_collection(LineCollection(x[mesh.boundary_edges], colors="k", linewidths=0.8))
    plot.draw_interfaces(ax, mesh, result.model.material_of_triangle)
    modes = _break_modes(result)
    first = {}
    for ev in result.events:
        first.setdefault(ev.bond, ev.mode)
    soft_modes = [first.get(int(b), "tension") for b in soft]
    shear_soft = bool(len(soft)) and any(m != "tension" for m in soft_modes)
    if shear_soft:  # faces softening in shear or crushing: their modes
        for mode, colour in _MODE_COLOURS.items():
            sel = [i for i, m in enumerate(soft_modes) if m == mode]
            if sel:
                ax.add_collection(
                    LineCollection(
                        soft_faces[sel],
                        colors=colour,
                        alpha=0.45,
                        linewidths=0.8,
                        label=f"{mode} (softening)",
                    )
                )
    elif len(soft):
        ax.add_collection(LineCollection(soft_faces, colors="0.6", linewidths=0.8))
    if (len(faces) and any(m != "tension" for m in modes)) or shear_soft:
        for mode, colour in _MODE_COLOURS.items():
            sel = [i for i, m in enumerate(modes) if m == mode]
            if sel:
                ax.add_collection(
                    LineCollection(faces[sel], colors=colour, linewidths=1.6, label=mode)
                )
        ax.legend(fontsize=8, title="failure mode", title_fontsize=8, loc="best")
    elif len(faces):
        lc = LineCollection(faces, array=np.arange(len(faces)), cmap="plasma", linewidths=1.6)
        ax.add_collection(lc)
        fig.colorbar(lc, ax=ax, shrink=0.8, label="order of breaking (bonds)")
    ax.set_aspect("equal")
    pad = 0.02 * float((hi - lo).max())
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_title(
        title or f"{result.model.kind}: {len(faces)} bonds broken, {len(soft)} softened",
        fontsize=9,
    )
    ax.set_xlabel("x (length)")
    ax.set_ylabel("y (length)")
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = atomic_path(path).with_suffix(".png")
    plot.save(fig, tmp)
    return finish(tmp, path)
