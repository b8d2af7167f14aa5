"""Files: gmsh/meshio import, VTU export, JSON (the summary of :mod:`dvstatic.report`),
PNG pictures.

Two functions and a container, meshio style: :func:`read_mesh` turns a mesh file
into a :class:`~dvstatic.Mesh` (physical line groups become named boundary parts),
:func:`write_vtu` writes a solution with everything a viewer needs. Every file is
written to a temporary name in the target folder and renamed, so a crash never
leaves a half-written file under the final name. meshio and matplotlib are imported
on first use.
"""

from __future__ import annotations

import contextlib
import io
import json
import logging
import os
from pathlib import Path

import numpy as np

from .errors import InputError
from .mesh import Mesh
from .report import CHECK_QUANTITIES, FIELDS, _szz, check_values, nodal_field, summary

log = logging.getLogger(__name__)

__all__ = [
    "read_mesh",
    "write_vtu",
    "write_bonds_vtu",
    "summary",
    "check_values",
    "CHECK_QUANTITIES",
    "write_json",
    "write_png",
    "atomic_path",
    "FIELDS",
    "nodal_field",
    "write_fracture_series",
    "write_fracture_curve",
    "write_crack_png",
    "crack_faces",
    "picture_view",
    "default_scale",
]


def atomic_path(path: Path) -> Path:
    """Temporary sibling of ``path`` (same folder, so the final rename is atomic)."""
    return path.with_name(f".{path.name}.{os.getpid()}.tmp")


def _finish(tmp: Path, path: Path) -> Path:
    os.replace(tmp, path)
    return path


def read_mesh(path: str | Path) -> Mesh:
    """Read a triangle mesh (gmsh ``.msh`` or any format meshio reads).

    Points must be planar (z = 0). Triangles (3- or 6-node; the corner nodes are
    used) become the mesh; points not used by any triangle are dropped. Line cells
    with a gmsh physical group become a named boundary part (the group's name, or
    ``"group<tag>"``).

    Raises
    ------
    ValueError
        Missing file, no triangles, non-planar points, or line groups that are not
        boundary edges of the triangles.
    """
    import meshio

    path = Path(path)
    if not path.is_file():
        raise InputError(f"mesh file not found: {path}", "path")
    said = io.StringIO()  # meshio prints its own errors: keep them off the terminal
    try:
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
            m = meshio.read(path)
    except (Exception, SystemExit) as exc:  # meshio raises many types, even SystemExit
        why = " ".join(said.getvalue().split()).removeprefix("Error: ")
        why = why or (str(exc) if not isinstance(exc, SystemExit) else "unknown format")
        raise InputError(f"cannot read mesh file {path}: {why}", "path") from None
    pts = np.asarray(m.points, dtype=float)
    if pts.shape[1] == 3:
        if np.any(np.abs(pts[:, 2]) > 1e-12 * max(1.0, np.abs(pts[:, :2]).max())):
            raise InputError(f"{path}: points are not planar (z != 0); dvstatic is 2-D", "path")
        pts = pts[:, :2]
    tris = [c.data[:, :3] for c in m.cells if c.type in ("triangle", "triangle6")]
    if not tris:
        raise InputError(
            f"{path}: no triangle cells found (cell types: {sorted({c.type for c in m.cells})})",
            "path",
        )
    tri = np.vstack(tris).astype(np.int64)
    used = np.unique(tri)
    remap = -np.ones(len(pts), dtype=np.int64)
    remap[used] = np.arange(len(used))
    parts: dict[str, list[np.ndarray]] = {}
    phys = m.cell_data.get("gmsh:physical")
    names: dict[int, str] = {}
    surfaces: dict[int, str] = {}
    for name, (tag, dim) in ((k, v[:2]) for k, v in m.field_data.items()):
        if int(dim) == 1:
            names[int(tag)] = name
        elif int(dim) == 2:
            surfaces[int(tag)] = name
    if phys is not None:
        for block, tags in zip(m.cells, phys, strict=True):
            if block.type not in ("line", "line3"):
                continue
            edges = block.data[:, :2].astype(np.int64)
            for tag in np.unique(tags):
                sel = edges[np.asarray(tags) == tag]
                if np.any(remap[sel] < 0):
                    raise InputError(
                        f"{path}: line group {tag} uses points outside the triangles", "path"
                    )
                parts.setdefault(names.get(int(tag), f"group{int(tag)}"), []).append(remap[sel])
    parts_arr = {k: np.vstack(v) for k, v in parts.items()}
    regions = _surface_regions(m, phys, surfaces)
    mesh = Mesh(pts[used], remap[tri], parts=parts_arr, regions=regions)
    log.info("read %s: %r", path, mesh)
    return mesh


def _surface_regions(m, phys, surfaces: dict[int, str]) -> dict[str, np.ndarray]:
    """Triangle indices (in the order the triangle blocks are stacked) of every physical
    surface group."""
    if phys is None:
        return {}
    out: dict[str, list[np.ndarray]] = {}
    offset = 0
    for block, tags in zip(m.cells, phys, strict=True):
        if block.type not in ("triangle", "triangle6"):
            continue
        tags = np.asarray(tags)
        for tag in np.unique(tags):
            name = surfaces.get(int(tag), f"surface{int(tag)}")
            out.setdefault(name, []).append(offset + np.flatnonzero(tags == tag))
        offset += len(block.data)
    return {k: np.concatenate(v) for k, v in out.items()}


def write_vtu(path: str | Path, solution, stress: bool = True, fe=None) -> Path:
    """Write a solution's continuum fields as VTU (ParaView), atomically.

    Content: 3-D points (z = 0) and the triangles; point data ``displacement`` (N, 3)
    and, with ``stress``, ``stress`` (N, 9: a 3x3 tensor, which ParaView recognises, of
    the default recovery of :meth:`Solution.stress`; ``szz`` is its out-of-plane
    component, nonzero in plane strain), ``stress_virial`` (N, 9: the lattice's
    force-based stress per Voronoi cell) and ``von_mises`` (N,); cell data ``area``
    (triangle area) and ``material`` (0: the base material, i: the i-th of
    ``model.materials``). With ``fe`` (an FE reference of the same problem, e.g.
    :func:`dvstatic.fem.solve`) also ``fe_displacement``, ``fe_stress`` (N, 9) and the
    differences lattice minus FE, ``displacement_difference`` and ``stress_difference``.
    The bonds and their tensions are in :func:`write_bonds_vtu`.
    """
    import meshio

    path = Path(path)
    mesh = solution.model.mesh
    point_data = {"displacement": np.c_[solution.u, np.zeros(mesh.n_points)]}
    if stress:
        for key, method in (("stress", None), ("stress_virial", "virial")):
            s = solution.stress(method)
            t9 = np.zeros((mesh.n_points, 9))
            t9[:, [0, 1, 3, 4]] = s.reshape(-1, 4)
            t9[:, 8] = _szz(solution, s)
            point_data[key] = t9
        point_data["von_mises"] = nodal_field(solution, "von_mises")
    if fe is not None:
        try:
            point_data.update(_fe_fields(solution, fe, point_data.get("stress")))
        except (ValueError, np.linalg.LinAlgError) as exc:  # the lattice fields still go
            log.warning("the FE fields are left out of %s: %s", Path(path).name, exc)
    cell_data = {
        "area": [np.asarray(mesh.triangle_areas, dtype=float)],
        "material": [np.asarray(solution.model.material_of_triangle, dtype=np.int32)],
    }
    out = meshio.Mesh(
        np.c_[mesh.points, np.zeros(mesh.n_points)],
        [("triangle", mesh.triangles)],
        point_data=point_data,
        cell_data=cell_data,
    )
    return _write_meshio(path, out)


def _fe_fields(solution, fe, stress9) -> dict:
    """The FE reference's fields at the lattice nodes and the differences from it."""
    x = solution.model.mesh.points
    n = len(x)
    ufe = np.asarray(fe.u, dtype=float).reshape(-1, 2)
    out = {
        "fe_displacement": np.c_[ufe, np.zeros(n)],
        "displacement_difference": np.c_[solution.u - ufe, np.zeros(n)],
    }
    s = fe.stress(x)
    t9 = np.zeros((n, 9))
    t9[:, [0, 1, 3, 4]] = s.reshape(-1, 4)
    t9[:, 8] = fe.out_of_plane_stress(x)
    out["fe_stress"] = t9
    if stress9 is not None:
        out["stress_difference"] = stress9 - t9
    return out


def write_bonds_vtu(path: str | Path, solution) -> Path:
    """Write the lattice's bonds as VTU line cells, atomically: point data
    ``displacement`` (N, 3), cell data ``tension`` (force; positive in tension) and
    ``length`` (undeformed bond length)."""
    import meshio

    path = Path(path)
    mesh = solution.model.mesh
    bonds = mesh.topology.bonds
    d = mesh.points[bonds[:, 1]] - mesh.points[bonds[:, 0]]
    out = meshio.Mesh(
        np.c_[mesh.points, np.zeros(mesh.n_points)],
        [("line", bonds)],
        point_data={"displacement": np.c_[solution.u, np.zeros(mesh.n_points)]},
        cell_data={"tension": [solution.tension()], "length": [np.hypot(d[:, 0], d[:, 1])]},
    )
    return _write_meshio(path, out)


def _write_meshio(path: Path, out) -> Path:
    import meshio

    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = atomic_path(path)
    meshio.write(tmp, out, file_format="vtu")
    return _finish(tmp, path)


def write_json(path: str | Path, data: dict) -> Path:
    """Write ``data`` as indented JSON, atomically."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = atomic_path(path)
    tmp.write_text(json.dumps(data, indent=2, default=_plain))
    return _finish(tmp, path)


def _plain(o):
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


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
    return _finish(tmp, path)


def write_fracture_series(folder: str | Path, result, name: str = "fracture") -> Path:
    """Write a fracture analysis as a VTU time series readable in ParaView.

    One ``<name>_NNNN.vtu`` per snapshot (and the final state) in ``folder``, listed
    with their event numbers as times in ``<name>.pvd`` (open that one). Each holds the
    bonds as line cells with ``stiffness`` (1 intact, 0 broken), ``broken`` (0/1) and
    ``strength`` (force), and the nodes with ``displacement`` (at the event's critical
    load), ``damage`` (mean stiffness loss of the node's bonds) and ``stress_virial``
    (N, 9: the damaged lattice's bond forces over each Voronoi cell; the recovered
    stress of a state is ``result.solution(k).stress()``).

    Returns
    -------
    Path
        The ``.pvd`` file.
    """
    import meshio

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    mesh = result.model.mesh
    bonds = mesh.topology.bonds
    pts = np.c_[mesh.points, np.zeros(mesh.n_points)]
    from .stress.virial import node_stress

    states = [(s.event, s.u, s.stiffness) for s in result.snapshots]
    last = len(result.events)
    states.append((last, result.u, result.stiffness))
    entries = []
    for k, (event, u, d) in enumerate(states):
        virial = np.zeros((mesh.n_points, 9))
        virial[:, [0, 1, 3, 4]] = node_stress(result.model.damaged(d), u).reshape(-1, 4)
        out = meshio.Mesh(
            pts,
            [("line", bonds)],
            point_data={
                "displacement": np.c_[u, np.zeros(mesh.n_points)],
                "damage": result.node_damage(d),
                "stress_virial": virial,
            },
            cell_data={
                "stiffness": [d],
                "broken": [(d <= 0).astype(np.int8)],
                "strength": [result.strength],
            },
        )
        file = f"{name}_{k:04d}.vtu"
        _write_meshio(folder / file, out)
        entries.append(f'    <DataSet timestep="{event}" part="0" file="{file}"/>')
    pvd = "\n".join(
        [
            '<?xml version="1.0"?>',
            '<VTKFile type="Collection" version="0.1">',
            "  <Collection>",
            *entries,
            "  </Collection>",
            "</VTKFile>",
            "",
        ]
    )
    path = folder / f"{name}.pvd"
    tmp = atomic_path(path)
    tmp.write_text(pvd)
    return _finish(tmp, path)


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
    return _finish(tmp, path)


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


def write_crack_png(path: str | Path, result, title: str | None = None) -> Path:
    """The crack pattern of a fracture analysis as a PNG, atomically: the body's
    outline, the Voronoi faces of the broken bonds coloured by the order they broke,
    those of softened (cracked, not yet broken) bonds in grey; a crack in a small part
    of the body is framed."""
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
    if len(soft):
        ax.add_collection(LineCollection(soft_faces, colors="0.6", linewidths=0.8))
    if len(faces):
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
    return _finish(tmp, path)
