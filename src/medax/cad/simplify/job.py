"""State shared by the steps of one fillet simplification: the tolerances, the working
copy with its maps, what each step found (medial curves, corner arcs, bridges, chains,
merged surfaces) and the blends kept so far (:class:`Job`), and a rebuilt, validated
solid (:class:`Attempt`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from OCP.TopoDS import TopoDS

from medax import tolerances
from medax.cad.simplify.chains import Chain
from medax.cad.simplify.fitted import (
    FittedSurface,
    GraphSetup,
)
from medax.cad.simplify.groups import Group
from medax.cad.simplify.local_measure import Measures
from medax.cad.simplify.medial import Medial
from medax.cad.simplify.specs import CornerSpec, FilletSpec
from medax.cad.simplify.surfaces import MergedSurface
from medax.cad.simplify.validate import (
    default_volume,
    volume,
)

#: Default deviation tolerance, relative to the part's diagonal (the issue's ``1e-5 x``).
DEVIATION_TOL = 1e-5
#: Largest accepted relative volume change.
VOLUME_TOL = 1e-6
#: Largest accepted relative change of the boundary's area: 25x the integrator's noise on
#: exact faces (up to 2.0e-7 on every part simplified, from NURBS copies of revolutions),
#: and below the 1.8e-5 more area of a merged face with a 0.35 mm bump in one pcurve, which
#: the analyzer and the sampled deviations passed.
AREA_TOL = 5e-6
#: Geometric tolerance of the construction, relative to the diagonal.
BUILD_TOL = tolerances.BUILD_TOL
#: A fitted surface is fitted to this share of the deviation tolerance (measured), and
#: taken up to ACCEPT_SHARE when no fit reaches it within its levels: the faces that reach
#: it keep their tangency across the medial curves (2e-3 rad on the 12-edge box; 9e-3 rad
#: when fitted to 0.4), and those whose fit stalls on a curvature jump off its knot lines
#: are merged (most of them stalled within 4x), still checked against the full tolerance.
FIT_SHARE, ACCEPT_SHARE = 0.1, 0.8
#: Deviation samples per face (n x n) for groups on a fitted surface.
FITTED_DEVIATION_SAMPLES = 12
#: The budgets below are CPU seconds of this process (``time.process_time``), not wall
#: time, so that what is removed does not depend on the machine's load; on an idle machine
#: the two are the same.
#: CPU seconds the search for failing fillets may take after the first rebuild failed.
ISOLATION_BUDGET = 300.0
#: CPU seconds the whole simplification may take before the search stops starting attempts
#: (each as long as the first one is counted), so that a part with its reading and writing
#: ends within 10 minutes on an idle machine.
RUN_BUDGET = 480.0
#: CPU seconds of the run after which the second chances (the cylinder field's pass, riders
#: tried as plain fillets) are no longer started: each is another pass over the fitted
#: faces, and the first rebuild, and the search after it, need the rest of ``RUN_BUDGET``.
SECOND_PASS_BUDGET = 0.4 * RUN_BUDGET
#: Riders tried one at a time as plain fillets on their kept base, at most (each try is a
#: pass over the fitted faces).
MAX_RIDER_TRIES = 8
#: Marker in the surface table: this supporting plane gets a fitted surface per attempt.
FITTED = "fitted"


@dataclass
class Attempt:
    shape: Any
    groups: list[Group]
    faces: list[Any]
    deviation: float
    volume: float
    origin: tuple[int, ...]
    halves_origin: dict[int, list[int]]
    kinds: dict[int, str]
    fit_error: float = 0.0
    fit_dv: float = 0.0
    area_change: float = 0.0
    volume_before: float = 0.0  # the input's volume that ``volume`` is measured against


@dataclass
class Job:
    """State shared by the steps of one :func:`simplify` run: the working copy and its
    maps, the medial curves, corner arcs, bridges ((rider, base) -> edge), merged surfaces,
    fitted-surface cache, the fillets
    still tried (``specs``), the blends kept with their reasons, and tolerances."""

    work: Any
    fmap: Any
    emap: Any
    diag: float
    tol: float
    say: Callable[[str], None]
    kept: dict[int, str]
    medials: dict[int, Medial] = field(default_factory=dict)
    specs: dict[int, FilletSpec] = field(default_factory=dict)
    corners: dict[int, CornerSpec] = field(default_factory=dict)
    arcs: dict[int, list[Any]] = field(default_factory=dict)
    bridges: dict[tuple[int, int], Any] = field(default_factory=dict)
    surfaces: dict[int, MergedSurface | str] = field(default_factory=dict)
    cache: dict[tuple[int, ...], FittedSurface | str] = field(default_factory=dict)
    # (support, member origins) -> the height-field fit's setup, shared by probe and full fit
    setups: dict[tuple[int, ...], GraphSetup | str] = field(default_factory=dict)
    # the last split kept by a fit round and the tool edges it was made with (:func:`split_job`)
    last_split: tuple[list[Any], Any] | None = None
    exact: dict[tuple[Any, ...], MergedSurface | str] = field(default_factory=dict)
    area0: float | None = None  # the input's boundary area (measured at the first attempt)
    volume0: float | None = None  # the input's volume (measured at the first attempt)
    volume_ref: float | None = None  # its volume by the default integrator (a denominator)
    whole: dict[int, int] = field(default_factory=dict)  # fillet -> face it merges into whole
    # fillet -> its supporting face that has no surface for its half (why it was kept)
    no_surface: dict[int, int] = field(default_factory=dict)
    # fillets whose own piece held the misfit of that face (the face is fitted without them)
    own_misfit: set[int] = field(default_factory=set)
    # chains of tangent fillets (:mod:`.chains`): each goes whole or not at all
    chains: list[Chain] = field(default_factory=list)
    chain_links: set[tuple[int, int]] = field(default_factory=set)
    # rider -> (the fillet it rides on with no bridge, its medial curve, why it was kept)
    unbridged: dict[int, tuple[int, Medial, str]] = field(default_factory=dict)
    # whether cylinders the ring route refuses take the cylinder field (the second pass:
    # :func:`cylinder_pass`), and the fillets a failing face drops first then
    cylinder_field: bool = False
    prefer: set[int] = field(default_factory=set)
    # the integrals and deviations of the changed groups, kept from one attempt to the next
    # (keyed by the faces' geometry: :func:`.local_measure.face_key`)
    measures: Measures = field(default_factory=Measures)
    # the new edges' pcurves, kept from one attempt to the next (keyed by the surface's and
    # the curves' geometry: :func:`.rebuild._pcurve_key`)
    pcurves: Measures = field(default_factory=Measures)
    # whether an attempt is also refused when OCCT's default mass properties would read its
    # merged faces as a volume change above VOLUME_TOL (``simplify(strict_volume=True)``)
    strict_volume: bool = False

    @property
    def vol0(self) -> float:
        """The input's volume (:func:`.validate.volume`), measured when first needed: a
        run in which no rebuild gets that far does without it (Gauss-Kronrod took 197 s on
        a 68-face part whose every fit failed)."""
        if self.volume0 is None:
            self.volume0 = volume(self.work)
        return self.volume0

    @property
    def vol_ref(self) -> float:
        """The input's volume by OCCT's default integrator: the denominator of the relative
        volume changes measured on the changed faces (1e-3 off changes a 1e-6 change by
        1e-9; Gauss-Kronrod on a 94-face input took 188 s where the denominator needs no
        digits from it). The whole-solid check compares with :attr:`vol0`."""
        if self.volume_ref is None:
            self.volume_ref = default_volume(self.work)
        return self.volume_ref

    @property
    def btol(self) -> float:
        """Length tolerance of the construction."""
        return BUILD_TOL * self.diag

    def face(self, i: int) -> Any:
        """Face ``i`` (0-based) of the working solid."""
        return TopoDS.Face(self.fmap.FindKey(i + 1))
