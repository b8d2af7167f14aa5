"""The options of :func:`dvstatic.fracture`, listed once.

:class:`FractureOptions` is the single source, as :class:`~dvstatic.SolveOptions` is for
``dv.solve``: ``dv.fracture``'s option keywords and their docstring, the options of the
scene's ``[fracture]`` table and the option table in ``docs/api.md`` are derived from its
fields. The strengths (``ft``, ``gf``, ``weibull``) are the material's and stay keywords
of :func:`dvstatic.fracture` itself.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass

from .._checks import check_choice, check_int, check_positive, check_real
from ..errors import InputError
from ..solvers.options import option
from .criteria import CRITERIA, REGISTRY
from .criteria.tension import RENAMED

__all__ = ["FractureOptions", "MAX_RANK"]

#: largest low-rank update (columns) before the stiffness is factorised afresh
MAX_RANK = 3000


@dataclass(frozen=True)
class FractureOptions:
    """How a fracture analysis runs (validated on construction; see each field's doc)."""

    max_events: int = option(1000, "stop after this many events (>= 1)", "int")
    criterion: str = option(
        "stress",
        "what an intact bond compares with its strength: `stress`, the normal stress across "
        "its Voronoi face (a Rankine criterion, unaffected by compression along the face); "
        "`mohr-coulomb`, Coulomb's line `|tau| + sigma_n tan(phi) = c` with the tension "
        "cut-off `ft` on the face and on the planes tilted out of the plane through it (the "
        "3-D envelope with the out-of-plane principal stress; needs `cohesion` and "
        "`friction_angle`); or `bond-tension`, the bond's force (which compression along "
        "the face raises: under tension `s` and compression `3 s` it cracks at about "
        "`ft / 2.6`), refused where its first event comes 5 % before the face stress's",
        "string",
        CRITERIA,
    )
    contact: bool = option(
        True,
        "cracks close: a face cracked in tension carries normal compression again once it "
        "closes (unilateral contact, the status made consistent within each event); False: "
        "cracked faces carry nothing",
        "bool",
    )
    teeth: int = option(
        30, "saw-tooth steps of a cracked bond's softening (with `gf`; 2 to 1000)", "int"
    )
    stop_load_ratio: float = option(
        0.01,
        "stop once the load falls below this fraction of the peak, in [0, 1) (0: never)",
        "number",
    )
    fragment: float = option(
        0.01,
        "a piece no longer held by the supports stops the analysis if it carries load or "
        "has more than this fraction of the nodes, in [0, 1]; smaller unloaded fragments "
        "are left hanging",
        "number",
    )
    max_rank: int = option(
        240,
        f"largest low-rank update (columns, one per bond of the damaged triangles, 0 to "
        f"{MAX_RANK}) before the stiffness is factorised afresh (0: refactorise at every "
        "event, the reference path)",
        "int",
    )
    max_seconds: float | None = option(
        None,
        "stop the event loop after this many seconds of wall time (> 0; None: no limit), "
        "keeping the events so far (`stop_reason` `time_limit`)",
        "number",
    )
    blas_threads: int | None = option(
        1,
        "threads of the dense algebra in the event loop (the low-rank updates' small "
        "solves; >= 1): 1 by default, as many threads fight for the cores of a shared "
        "machine and gain nothing on these sizes; None: as the BLAS library decides",
        "int",
    )
    snapshots: int = option(
        50,
        "about this many states kept for the VTU series (>= 1), spread over the events "
        "actually run; the peak and the last state are always among them",
        "int",
    )
    snapshot_every: int | None = option(
        None,
        "keep the state every this many events instead (>= 1; and the peak and the last)",
        "int",
        scene=False,
    )
    progress: bool = option(False, "show a progress bar of the events (tqdm)", "bool", scene=False)
    check_stability: bool = option(
        True,
        "refuse a lattice whose stiffness with these supports is not positive definite "
        "(`UnstableError` before the first event, as `dv.solve` does), and stop "
        "(`stop_reason` `unstable`) where a fresh factorisation of the damaged stiffness "
        "finds it indefinite; False: break it anyway",
        "bool",
    )

    def __post_init__(self) -> None:
        check_int("max_events", self.max_events, minimum=1)
        if self.criterion in RENAMED and self.criterion not in REGISTRY:
            raise InputError(RENAMED[self.criterion], "criterion")
        check_choice("criterion", self.criterion, tuple(REGISTRY))  # with any registered since
        check_int("teeth", self.teeth, minimum=2, maximum=1000)
        check_int("max_rank", self.max_rank, minimum=0, maximum=MAX_RANK)
        check_int("snapshots", self.snapshots, minimum=1)
        if self.blas_threads is not None:
            check_int("blas_threads", self.blas_threads, minimum=1)
        if self.max_seconds is not None:
            check_positive("max_seconds", self.max_seconds)
        if self.snapshot_every is not None:
            check_int("snapshot_every", self.snapshot_every, minimum=1)
        _fraction("stop_load_ratio", self.stop_load_ratio, closed=False)
        _fraction("fragment", self.fragment, closed=True)
        if not isinstance(self.contact, bool):
            raise TypeError(f"contact must be True or False, got {self.contact!r}")
        for name in ("progress", "check_stability"):
            value = getattr(self, name)
            if not isinstance(value, bool):
                raise TypeError(f"{name} must be True or False, got {value!r}")

    @classmethod
    def from_kwargs(cls, base: FractureOptions | None = None, **kwargs) -> FractureOptions:
        """Options from keywords, on top of ``base``.

        Raises
        ------
        TypeError
            An unknown keyword (the message lists the accepted ones).
        """
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(kwargs) - names)
        if unknown:
            raise TypeError(
                f"unknown fracture option(s) {', '.join(map(repr, unknown))}; accepted: "
                + ", ".join(sorted(names))
            )
        if base is not None and not isinstance(base, cls):
            raise TypeError(f"options must be a FractureOptions, got {type(base).__name__}")
        return dataclasses.replace(base or cls(), **kwargs)


def _fraction(name: str, value, closed: bool) -> float:
    """A finite number in [0, 1] (``closed``) or [0, 1)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        check_real(name, value)  # the TypeError
    v = float(value)
    if not math.isfinite(v) or v < 0 or (v > 1 if closed else v >= 1):
        bound = "[0, 1]" if closed else "[0, 1)"
        raise InputError(f"{name} must lie in {bound}, got {value!r}", name)
    return v
