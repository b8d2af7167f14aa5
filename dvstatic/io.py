"""Files: gmsh/meshio import, VTU export, JSON (the summary of :mod:`dvstatic.report`),
the pictures (:mod:`dvstatic.pictures`, re-exported here).

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
from pathlib import Path

import numpy as np

from ._atomic import atomic_path, finish
from .errors import InputError
from .mesh import Mesh
from .pictures import (
    crack_faces,
    default_scale,
    figure_size,
    picture_view,
    write_crack_png,
    write_fracture_curve,
    write_png,
)
from .report import CHECK_QUANTITIES, FIELDS, _szz, check_values, nodal_field, summary

log = logging.getLogger(__name__)

__all__ = [
    "read_mesh",
    "write_mesh",
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
    "figure_size",
]


_finish = finish


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


def write_mesh(path: str | Path, mesh: Mesh) -> Path:
    """Write a mesh as gmsh 2.2 (``.msh``), atomically, so that :func:`read_mesh` gives
    it back: the same points and triangles in the same order, every boundary part a
    physical line group of its name, every region a physical surface group of its name
    (the triangles of no region a group ``"body"``). gmsh opens it too. A mesh read
    back has no generator recipe: it is calibrated and corrected as an imported mesh
    (local spread, regional isotropy).

    Raises
    ------
    ValueError
        A suffix other than ``.msh``, a periodic mesh, or a part and a region of the
        same name.
    """
    import meshio

    path = Path(path)
    if path.suffix != ".msh":
        raise InputError(f"write_mesh writes gmsh files (.msh), got {path.name!r}", "path")
    if mesh.is_periodic:
        raise InputError("a periodic mesh has no gmsh form (its images are lost)", "mesh")
    tri_tag, field = _surface_tags(mesh)
    lines, line_tags = [], []
    for name, edges in mesh.parts.items():
        if name in field:
            raise InputError(f"part and region of the same name {name!r}", "mesh")
        field[name] = np.array([len(field) + 1, 1])
        lines.append(np.asarray(edges, dtype=np.int64))
        line_tags.append(np.full(len(edges), field[name][0]))
    cells = ([("line", np.vstack(lines))] if lines else []) + [("triangle", mesh.triangles)]
    tags = ([np.concatenate(line_tags)] if lines else []) + [tri_tag]
    out = meshio.Mesh(
        np.c_[mesh.points, np.zeros(mesh.n_points)],
        cells,
        cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags},
        field_data=field,
    )
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = atomic_path(path)
    meshio.write(tmp, out, file_format="gmsh22", binary=False)
    return _finish(tmp, path)


def _surface_tags(mesh: Mesh) -> tuple[np.ndarray, dict]:
    """Every triangle's physical surface tag (M,) and the groups' field data."""
    tag = np.zeros(mesh.n_triangles, dtype=np.int64)
    field: dict[str, np.ndarray] = {}
    for name, idx in mesh.regions.items():  # disjoint (Mesh refuses overlaps)
        field[name] = np.array([len(field) + 1, 2])
        tag[idx] = field[name][0]
    if not tag.all():
        name = "body" if "body" not in field else "body_rest"
        field[name] = np.array([len(field) + 1, 2])
        tag[tag == 0] = field[name][0]
    return tag, field


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


def write_fracture_series(folder: str | Path, result, name: str = "fracture") -> Path:
    """Write a fracture analysis as a VTU time series readable in ParaView.

    One ``<name>_NNNN.vtu`` per snapshot (and the final state) in ``folder``, listed
    with their event numbers as times in ``<name>.pvd`` (open that one). Each holds the
    bonds as line cells with ``stiffness`` (1 intact, 0 broken), ``broken`` (0/1),
    ``mode`` (how a broken bond failed: 0 intact, 1 tension, 2 shear, 3 crushing, 4 out-of-plane),
    ``closed`` (1: a cracked face closed, carrying compression) and
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
    from .crack.criteria import MODES
    from .stress.virial import node_stress

    code = np.zeros(mesh.n_bonds, dtype=np.int8)
    for ev in result.events:
        if ev.broken:
            code[ev.bond] = 1 + MODES.index(ev.mode)
    states = [(s.event, s.u, s.stiffness, s.closed) for s in result.snapshots]
    last = len(result.events)
    final = np.zeros(mesh.n_bonds, dtype=bool)
    if result.events:
        final[list(result.events[-1].closed)] = True
    states.append((last, result.u, result.stiffness, final if final.any() else None))
    entries = []
    for k, (event, u, d, closed) in enumerate(states):
        virial = np.zeros((mesh.n_points, 9))
        damaged = result.model.damaged(d, closed)
        virial[:, [0, 1, 3, 4]] = node_stress(damaged, u).reshape(-1, 4)
        closed = np.zeros(mesh.n_bonds, bool) if closed is None else closed
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
                "mode": [np.where(d <= 0, code, 0).astype(np.int8)],
                "closed": [closed.astype(np.int8)],
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
