"""A validated scene turned into a mesh, a model, supports, loads and solver options."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..crack.options import FractureOptions
from ..errors import CalibrationError, InputError
from ..io import read_mesh
from ..lattice import DV, RV
from ..mesh import generators as meshgen
from ..mesh.domain import Circle, Domain, Polygon, rectangle_domain
from ..mesh.graded import size_near
from ..mesh.locate import snap_point
from ..problem import BodyForce, Fix, PointLoad, Pressure, Traction, nearest_node
from ..problem.select import LOAD_SNAP_TOLERANCE, SNAP_TOLERANCE
from .schema import FRACTURE_KEYS, SOLVER_KEYS, SceneError

__all__ = ["Scene"]


@dataclass(frozen=True)
class Scene:
    """A validated scene: ``data`` holds every key with its default filled in."""

    path: Path
    data: dict

    @property
    def name(self) -> str:
        return self.data["output"]["name"] or self.path.stem

    def _err(self, key: str, exc: Exception) -> SceneError:
        return SceneError(self.path, key, str(exc))

    def build_mesh(self):
        """The mesh described by ``[mesh]``."""
        m = self.data["mesh"]
        if m["type"] == "file":
            return self._read_mesh(m["path"])
        holes = [self._loop(f"mesh.holes[{i}]", h) for i, h in enumerate(m["holes"])]
        regions = [self._loop(f"mesh.regions[{i}]", r) for i, r in enumerate(m["regions"])]
        kind = None if m["kind"] == "auto" else m["kind"]
        common = {"kind": kind, "jitter": m["jitter"], "seed": m["seed"]}
        try:
            domain = Domain(self._outer(m), tuple(holes), tuple(regions))
            if m["refine_near"]:
                h = size_near(domain, m["refine_near"], m["h_near"], m["h"], m["grading"])
                return meshgen.generate(domain, h, **common)
            if m["type"] == "rectangle" and not holes:
                return meshgen.rectangle(
                    m["width"], m["height"], m["h"], regions=tuple(regions), **common
                )
            return meshgen.generate(domain, m["h"], **common)
        except InputError as exc:
            raise self._err(_MESH_KEYS.get(exc.param, "mesh"), exc) from None

    def _read_mesh(self, path: str):
        p = Path(path)
        if not p.is_absolute():
            p = self.path.parent / p
        if not p.is_file():
            raise SceneError(self.path, "mesh.path", f"mesh file not found: {p}")
        try:
            return read_mesh(p)
        except InputError as exc:
            raise self._err("mesh.path", exc) from None

    def _loop(self, key: str, h: dict):
        """A hole or region loop: a circle or a polygon, named."""
        try:
            if h["type"] == "circle":
                return Circle(tuple(h["center"]), h["radius"], h["name"])
            return Polygon(np.asarray(h["vertices"]), (h["name"],) * len(h["vertices"]))
        except (InputError, TypeError) as exc:
            raise self._err(key, exc) from None

    def _outer(self, m: dict):
        if m["type"] == "rectangle":
            return rectangle_domain(m["width"], m["height"]).outer
        if m["type"] == "polygon":
            v = np.asarray(m["vertices"])
            names = m["names"] or [f"edge{i}" for i in range(len(v))]
            if len(names) != len(v):
                raise SceneError(
                    self.path, "mesh.names", f"{len(names)} names for {len(v)} polygon edges"
                )
            return Polygon(v, tuple(names))
        return Circle(tuple(m["center"]), m["radius"], "boundary")

    def build_model(self, mesh):
        """The DV or RV model of ``[model]``, ``[material]`` and ``[[materials]]``."""
        cls = DV if self.data["model"]["type"] == "DV" else RV
        mat = self.data["material"]
        for i, other in enumerate(self.data["materials"]):
            if other["region"] not in mesh.regions:
                known = ", ".join(repr(k) for k in mesh.regions) or "none"
                raise SceneError(
                    self.path,
                    f"materials[{i}].region",
                    f"unknown region {other['region']!r}; the mesh's regions: {known}",
                )
        materials = {m["region"]: (m["E"], m["nu"]) for m in self.data["materials"]}
        try:
            return cls(
                mesh,
                mat["E"],
                mat["nu"],
                calibration=self.data["model"]["calibration"],
                bonds=self.data["model"]["bonds"],
                boundary_cells=self.data["model"]["boundary_cells"],
                anisotropy=self.data["model"]["anisotropy"],
                method=self.data["model"].get("method"),
                plane=mat["plane"],
                thickness=mat["thickness"],
                materials=materials or None,
            )
        except CalibrationError as exc:
            raise self._err("material.nu", exc) from None
        except InputError as exc:
            raise self._err(_MODEL_KEYS.get(exc.param, "material"), exc) from None

    def _edges(self, mesh, ld: dict, key: str):
        """The part of a traction or pressure, or with ``within`` its edges whose two
        ends lie in the box (a loading platen, a strip)."""
        part = self._nodes(mesh, ld, key)
        if ld["within"] is None:
            return part
        x0, x1, y0, y1 = ld["within"]
        edges = mesh.part_edges(part)
        p = mesh.points[edges]
        keep = np.all(
            (p[..., 0] >= x0) & (p[..., 0] <= x1) & (p[..., 1] >= y0) & (p[..., 1] <= y1), axis=1
        )
        if not keep.any():
            raise SceneError(
                self.path, f"{key}.within", f"no edge of part {part!r} lies within {ld['within']}"
            )
        return edges[keep]

    def _nodes(self, mesh, item: dict, key: str, tolerance: float = SNAP_TOLERANCE):
        if item.get("at") is not None:
            try:
                return np.array([nearest_node(mesh, item["at"], tolerance)])
            except InputError as exc:
                raise SceneError(self.path, f"{key}.at", str(exc)) from None
        where = item["where"]
        if isinstance(where, str):
            if where not in mesh.parts:
                known = ", ".join(repr(k) for k in mesh.parts) or "none"
                raise SceneError(
                    self.path,
                    f"{key}.where",
                    f"unknown boundary part {where!r}; known parts: {known}",
                )
            return where
        arr = np.asarray(where)
        if arr.min() < 0 or arr.max() >= mesh.n_points:
            raise SceneError(
                self.path, f"{key}.where", f"node indices must lie in [0, {mesh.n_points})"
            )
        return arr

    def build_supports(self, mesh) -> list:
        out = []
        for i, s in enumerate(self.data["supports"]):
            x = Profile(s["x_at"]) if s["x_at"] is not None else s["x"]
            y = Profile(s["y_at"]) if s["y_at"] is not None else s["y"]
            out.append(Fix(self._nodes(mesh, s, f"supports[{i}]"), x=x, y=y))
        return out

    def build_loads(self, mesh, held: bool = False) -> list:
        """The ``[[loads]]`` (``held``: the ``[[fracture.held]]`` loads) on ``mesh``."""
        out = []
        items, where = self.data["loads"], "loads"
        if held:
            items, where = (self.data["fracture"] or {}).get("held", []), "fracture.held"
        for i, ld in enumerate(items):
            key = f"{where}[{i}]"
            if ld["type"] == "body":
                region = ld["region"]
                if region is not None and region not in mesh.regions:
                    known = ", ".join(repr(k) for k in mesh.regions) or "none"
                    raise SceneError(
                        self.path, f"{key}.region", f"unknown region {region!r}; known: {known}"
                    )
                out.append(BodyForce(tuple(ld["value"]), region=region))
            elif ld["type"] == "traction":
                value = Profile(ld["value_at"]) if ld["value_at"] is not None else ld["value"]
                out.append(Traction(self._edges(mesh, ld, key), value))
            elif ld["type"] == "pressure":
                out.append(
                    Pressure(self._edges(mesh, ld, key), _pressure(ld), follower=ld["follower"])
                )
            else:
                nodes = self._nodes(mesh, ld, key, LOAD_SNAP_TOLERANCE)
                out.append(PointLoad(nodes, tuple(ld["value"])))
        return out

    def check_outputs(self, mesh) -> None:
        """Check ``[output]`` against the mesh before solving: every probe inside the
        mesh, every check's point in it (or within half the local spacing of a node), every
        ``part_stress`` name a boundary part.

        Raises
        ------
        SceneError
            Naming the key (``output.probes[i]``, ``output.part_stress[i]``).
        """
        o = self.data["output"]
        points = [(f"output.probes[{i}]", p) for i, p in enumerate(o["probes"])]
        points += [(f"output.checks[{i}].at", c["at"]) for i, c in enumerate(o["checks"])]
        for key, point in points:
            try:
                snap_point(mesh, np.asarray(point, dtype=float).reshape(1, 2))
            except InputError as exc:
                raise SceneError(self.path, key, str(exc)) from None
        v = o["view"]
        if v is not None:
            x = mesh.points
            inside = (x[:, 0] >= v[0]) & (x[:, 0] <= v[1]) & (x[:, 1] >= v[2]) & (x[:, 1] <= v[3])
            if not inside.any():
                raise SceneError(self.path, "output.view", f"{v} holds no node of the mesh")
        for i, name in enumerate(o["part_stress"]):
            if name not in mesh.parts:
                known = ", ".join(repr(k) for k in mesh.parts)
                raise SceneError(
                    self.path,
                    f"output.part_stress[{i}]",
                    f"unknown boundary part {name!r}; known parts: {known}",
                )

    def fracture_options(self) -> dict | None:
        """Keywords of :func:`dvstatic.fracture` from ``[fracture]`` (None without it)."""
        fr = self.data["fracture"]
        if fr is None:
            return None
        from ..crack import Weibull

        ft, gf = fr["ft"], fr["gf"]
        regions = fr["regions"]
        if regions:
            ft = {"default": ft, **{r["name"]: r["ft"] for r in regions}}
            with_gf = [r for r in regions if r["gf"] is not None]
            if with_gf and gf is None:
                raise SceneError(
                    self.path,
                    "fracture.gf",
                    "a region sets gf: give the default gf too (softening needs it everywhere)",
                )
            if gf is not None:
                gf = {"default": gf, **{r["name"]: r["gf"] for r in with_gf}}
        if fr["weibull_m"] is None and (fr["weibull_length"] or fr["seed"]):
            key = "fracture.weibull_length" if fr["weibull_length"] else "fracture.seed"
            raise SceneError(self.path, key, "applies to a random field: give weibull_m too")
        try:
            weibull = None
            if fr["weibull_m"] is not None:
                weibull = Weibull(fr["weibull_m"], fr["weibull_length"], fr["seed"])
        except InputError as exc:
            key = {"weibull.m": "weibull_m", "weibull.length": "weibull_length"}.get(
                exc.param, "seed"
            )
            raise self._err("fracture." + key, exc) from None
        try:
            options = FractureOptions(**{key: fr[key] for key in FRACTURE_KEYS})
        except InputError as exc:  # the types are the schema's: only values are left
            raise self._err(f"fracture.{exc.param}", exc) from None
        return dict(
            ft=ft,
            gf=gf,
            gf_shear=fr["gf_shear"],
            cohesion=fr["cohesion"],
            friction_angle=fr["friction_angle"],
            weibull=weibull,
            options=options,
        )

    def solve_options(self) -> dict:
        """Keyword options of :func:`dvstatic.solve` from ``[solver]``."""
        s = self.data["solver"]
        return {name: s[key] for key, name in SOLVER_KEYS.items()}


class Profile:
    """A value interpolated linearly along the line between two points (constant beyond
    its ends): rows ``[x0, y0, v...]`` and ``[x1, y1, v...]``. Called with points (m, 2)
    it returns (m,) for one value per row, (m, k) for k."""

    def __init__(self, rows):
        r = np.asarray(rows, dtype=float)
        self.a, self.b = r[0, :2], r[1, :2]
        self.va, self.vb = r[0, 2:], r[1, 2:]

    def __call__(self, x: np.ndarray) -> np.ndarray:
        d = self.b - self.a
        t = np.clip((np.asarray(x) - self.a) @ d / (d @ d), 0.0, 1.0)
        v = self.va + t[:, None] * (self.vb - self.va)
        return v[:, 0] if v.shape[1] == 1 else v

    def __repr__(self) -> str:
        ends = f"{self.a.tolist()}: {self.va.tolist()} -> {self.b.tolist()}: {self.vb.tolist()}"
        return f"Profile({ends})"


class Hydrostatic:
    """``p + gamma (level - y)`` below the level, ``p`` above it."""

    def __init__(self, p: float, gamma: float, level: float):
        self.p, self.gamma, self.level = p, gamma, level

    def __call__(self, x: np.ndarray) -> np.ndarray:
        return self.p + self.gamma * np.maximum(self.level - np.asarray(x)[:, 1], 0.0)

    def __repr__(self) -> str:
        return f"Hydrostatic(p={self.p:g}, gamma={self.gamma:g}, level={self.level:g})"


def _pressure(ld: dict):
    if ld["p_at"] is not None:
        return Profile(ld["p_at"])
    if ld["gamma"] is not None:
        return Hydrostatic(ld["p"] or 0.0, ld["gamma"], ld["level"])
    return ld["p"]


#: scene key of the mesh generator's arguments (InputError.param -> key path)
_MESH_KEYS = {
    "h": "mesh.h",
    "kind": "mesh.kind",
    "jitter": "mesh.jitter",
    "seed": "mesh.seed",
    "width": "mesh.width",
    "height": "mesh.height",
    "vertices": "mesh.vertices",
    "names": "mesh.names",
    "radius": "mesh.radius",
    "center": "mesh.center",
    "holes": "mesh.holes",
    "h_near": "mesh.h_near",
    "parts": "mesh.refine_near",
    "distance": "mesh.grading",
}
#: scene key of the model's arguments
_MODEL_KEYS = {
    "E": "material.E",
    "nu": "material.nu",
    "calibration": "model.calibration",
    "bonds": "model.bonds",
    "boundary_cells": "model.boundary_cells",
    "anisotropy": "model.anisotropy",
    "method": "model.method",
    "plane": "material.plane",
    "thickness": "material.thickness",
    "materials": "materials",
}
