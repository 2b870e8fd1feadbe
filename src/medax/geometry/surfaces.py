"""Parametric surfaces ``x = S(u, v)`` as embeddings of the parameter plane into space.

numpy only. Each class implements :class:`medax.geometry.embedding.Embedding` with an exact
(analytic) jacobian, vectorised over points: ``evaluate(p)`` maps ``p`` (n, 2) to (n, 3),
``jacobian(p)`` gives ``[dS/du, dS/dv]`` as (n, 3, 2). Parametrisations follow OpenCASCADE's
(``Geom_*`` surfaces), so a CAD face's pcurves can be used as they are: the frame
``origin, x, y, z`` is orthonormal, ``u`` the angle around ``z`` (radians) where relevant.

- plane:    ``S = o + u x + v y``
- cylinder: ``S = o + r (cos u x + sin u y) + v z``
- cone:     ``S = o + (r + v sin a)(cos u x + sin u y) + v cos a z`` (``a`` semi-angle)
- sphere:   ``S = o + r cos v (cos u x + sin u y) + r sin v z``
- torus:    ``S = o + (R + r cos v)(cos u x + sin u y) + r sin v z``
- NURBS:    tensor-product rational B-spline, poles (nu, nv, 3), optional weights (nu, nv)
- revolution: ``S = R(u) (C(v) - o) + o``, ``C`` a :class:`Profile` turned by the angle
  ``u`` about the axis through ``o`` along ``z`` (right hand)
- extrusion:  ``S = C(u) + v d``, ``C`` a :class:`Profile`, ``d`` a unit direction
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from medax.errors import InputError
from medax.geometry import kernels
from medax.geometry._rows import points2d
from medax.geometry._types import FloatArray
from medax.geometry.basis_kernel import span_basis_rows
from medax.geometry.bspline import POWER_BASIS_MAX_DEGREE, BSpline
from medax.geometry.nurbs_kernel import jet_rows


def _p(p: FloatArray) -> tuple[FloatArray, FloatArray]:
    a = points2d(p)
    return a[:, 0], a[:, 1]


@dataclass(frozen=True)
class Frame:
    """An orthonormal frame: ``origin`` (3,), axes ``x``, ``y``, ``z`` (3,) each."""

    origin: FloatArray
    x: FloatArray
    y: FloatArray
    z: FloatArray

    @classmethod
    def make(cls, origin, x, y, z=None) -> Frame:  # type: ignore[no-untyped-def]
        """A frame from possibly unnormalised axes (``z = x cross y`` when omitted)."""
        o = np.asarray(origin, dtype=np.float64).reshape(3)
        xa = np.asarray(x, dtype=np.float64).reshape(3)
        ya = np.asarray(y, dtype=np.float64).reshape(3)
        xa = xa / np.linalg.norm(xa)
        ya = ya - xa * float(xa @ ya)
        ya = ya / np.linalg.norm(ya)
        za = np.cross(xa, ya) if z is None else np.asarray(z, dtype=np.float64).reshape(3)
        za = za / np.linalg.norm(za)
        if abs(abs(float(np.dot(np.cross(xa, ya), za))) - 1.0) > 1e-9:
            raise InputError("surface frame axes are not orthonormal")
        return cls(o, xa, ya, za)

    def radial(self, u: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``cos u x + sin u y`` and its u-derivative, each (n, 3)."""
        c, s = np.cos(u)[:, None], np.sin(u)[:, None]
        return c * self.x + s * self.y, -s * self.x + c * self.y


class _Surface:
    dim = 3
    is_identity = False

    def evaluate(self, p: FloatArray) -> FloatArray:  # pragma: no cover - abstract
        raise NotImplementedError

    def jacobian(self, p: FloatArray) -> FloatArray:  # pragma: no cover - abstract
        raise NotImplementedError

    def normal(self, p: FloatArray) -> FloatArray:
        """Unit normals ``dS/du x dS/dv`` normalised, (n, 3) (NaN at singular points)."""
        j = self.jacobian(p)
        n = np.cross(j[:, :, 0], j[:, :, 1])
        norm = np.linalg.norm(n, axis=1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            return n / norm


def _stack(du: FloatArray, dv: FloatArray) -> FloatArray:
    out = np.empty((*np.shape(du), 2))
    out[..., 0], out[..., 1] = du, dv
    return out


@dataclass(frozen=True)
class PlaneSurface(_Surface):
    frame: Frame

    def evaluate(self, p: FloatArray) -> FloatArray:
        u, v = _p(p)
        f = self.frame
        return f.origin + u[:, None] * f.x + v[:, None] * f.y

    def jacobian(self, p: FloatArray) -> FloatArray:
        u, _ = _p(p)
        n = len(u)
        return _stack(np.broadcast_to(self.frame.x, (n, 3)), np.broadcast_to(self.frame.y, (n, 3)))


@dataclass(frozen=True)
class CylinderSurface(_Surface):
    frame: Frame
    radius: float

    def evaluate(self, p: FloatArray) -> FloatArray:
        u, v = _p(p)
        rad, _ = self.frame.radial(u)
        return self.frame.origin + self.radius * rad + v[:, None] * self.frame.z

    def jacobian(self, p: FloatArray) -> FloatArray:
        u, _ = _p(p)
        _, drad = self.frame.radial(u)
        return _stack(self.radius * drad, np.broadcast_to(self.frame.z, (len(u), 3)))


@dataclass(frozen=True)
class ConeSurface(_Surface):
    frame: Frame
    radius: float
    semi_angle: float

    def evaluate(self, p: FloatArray) -> FloatArray:
        u, v = _p(p)
        rad, _ = self.frame.radial(u)
        a = self.semi_angle
        r = (self.radius + v * np.sin(a))[:, None]
        return self.frame.origin + r * rad + (v * np.cos(a))[:, None] * self.frame.z

    def jacobian(self, p: FloatArray) -> FloatArray:
        u, v = _p(p)
        rad, drad = self.frame.radial(u)
        a = self.semi_angle
        r = (self.radius + v * np.sin(a))[:, None]
        return _stack(r * drad, np.sin(a) * rad + np.cos(a) * self.frame.z)


@dataclass(frozen=True)
class SphereSurface(_Surface):
    frame: Frame
    radius: float

    def evaluate(self, p: FloatArray) -> FloatArray:
        u, v = _p(p)
        rad, _ = self.frame.radial(u)
        r = self.radius
        return self.frame.origin + r * (
            np.cos(v)[:, None] * rad + np.sin(v)[:, None] * self.frame.z
        )

    def jacobian(self, p: FloatArray) -> FloatArray:
        u, v = _p(p)
        rad, drad = self.frame.radial(u)
        r = self.radius
        cv, sv = np.cos(v)[:, None], np.sin(v)[:, None]
        return _stack(r * cv * drad, r * (-sv * rad + cv * self.frame.z))


@dataclass(frozen=True)
class TorusSurface(_Surface):
    frame: Frame
    major_radius: float
    minor_radius: float

    def evaluate(self, p: FloatArray) -> FloatArray:
        u, v = _p(p)
        rad, _ = self.frame.radial(u)
        big, r = self.major_radius, self.minor_radius
        ring = (big + r * np.cos(v))[:, None]
        return self.frame.origin + ring * rad + (r * np.sin(v))[:, None] * self.frame.z

    def jacobian(self, p: FloatArray) -> FloatArray:
        u, v = _p(p)
        rad, drad = self.frame.radial(u)
        big, r = self.major_radius, self.minor_radius
        ring = (big + r * np.cos(v))[:, None]
        dv = (-r * np.sin(v))[:, None] * rad + (r * np.cos(v))[:, None] * self.frame.z
        return _stack(ring * drad, dv)


# ---- swept surfaces --------------------------------------------------------------------------
#: the kinds of :class:`Profile`
PROFILE_KINDS = ("line", "ellipse", "hyperbola", "parabola", "nurbs")


@dataclass(frozen=True)
class Profile:
    """A space curve ``C(t)`` in OpenCASCADE's own parameter ``t`` (``Geom_*`` curves), the
    generatrix of a swept surface. ``frame``'s origin ``o`` and axes ``x``, ``y``:

    - ``line``:      ``C = o + t x`` (``t`` a length)
    - ``ellipse``:   ``C = o + a cos t x + b sin t y`` (a circle when ``a = b``)
    - ``hyperbola``: ``C = o + a cosh t x + b sinh t y``
    - ``parabola``:  ``C = o + t^2 / (4 a) x + t y`` (``a`` the focal length)
    - ``nurbs``:     ``spline`` at ``(t - t0) / (t1 - t0)`` (its knot domain ``[t0, t1]``,
      which :class:`~medax.geometry.bspline.BSpline` maps onto ``[0, 1]``); with
      ``periodic`` one period of a periodic curve, ``t`` taken modulo ``t1 - t0``
    """

    kind: str
    frame: Frame
    a: float = 1.0
    b: float = 1.0
    spline: BSpline | None = None
    t0: float = 0.0
    t1: float = 1.0
    periodic: bool = False

    def __post_init__(self) -> None:
        if self.kind not in PROFILE_KINDS:
            raise InputError(f"profile kind must be one of {PROFILE_KINDS}, got {self.kind!r}")
        if self.kind == "nurbs" and (self.spline is None or not self.t1 > self.t0):
            raise InputError("a nurbs profile needs its spline and a knot domain t0 < t1")

    def evaluate(self, t: FloatArray) -> FloatArray:
        """Points ``C(t)`` (n, 3) at parameters ``t`` (n,)."""
        return self.jet(t)[0]

    def jet(self, t: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``C(t)`` and ``C'(t)``, each (n, 3), at parameters ``t`` (n,)."""
        t = np.asarray(t, dtype=np.float64).reshape(-1)
        f = self.frame
        if self.kind == "nurbs":
            assert self.spline is not None
            span = self.t1 - self.t0
            s = (np.mod(t - self.t0, span) if self.periodic else t - self.t0) / span
            return self.spline.evaluate(s), self.spline.derivative(s) / span
        tc = t[:, None]
        if self.kind == "line":
            return f.origin + tc * f.x, np.broadcast_to(f.x, (len(t), 3)).copy()
        if self.kind == "parabola":
            a = self.a
            p = f.origin + tc**2 / (4.0 * a) * f.x + tc * f.y
            return p, tc / (2.0 * a) * f.x + f.y
        if self.kind == "ellipse":
            c, s_, dc, ds = np.cos(tc), np.sin(tc), -np.sin(tc), np.cos(tc)
        else:  # hyperbola
            c, s_, dc, ds = np.cosh(tc), np.sinh(tc), np.sinh(tc), np.cosh(tc)
        p = f.origin + self.a * c * f.x + self.b * s_ * f.y
        return p, self.a * dc * f.x + self.b * ds * f.y


@dataclass(frozen=True)
class RevolutionSurface(_Surface):
    """``profile`` turned by the angle ``u`` (radians) about the axis through ``origin``
    (3,) along the unit ``axis`` (3,); ``v`` is the profile's parameter."""

    origin: FloatArray
    axis: FloatArray
    profile: Profile

    def _turn(self, u: FloatArray, w: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Vectors ``w`` (n, 3) turned by ``u`` (n,) about the axis, and their u-derivative."""
        z = self.axis
        along = (w @ z)[:, None] * z
        perp = w - along
        side = np.cross(z, w)
        c, s = np.cos(u)[:, None], np.sin(u)[:, None]
        return along + c * perp + s * side, -s * perp + c * side

    def evaluate(self, p: FloatArray) -> FloatArray:
        u, v = _p(p)
        turned, _ = self._turn(u, self.profile.evaluate(v) - self.origin)
        return self.origin + turned

    def jacobian(self, p: FloatArray) -> FloatArray:
        u, v = _p(p)
        c, dc = self.profile.jet(v)
        _, du = self._turn(u, c - self.origin)
        dv, _ = self._turn(u, dc)
        return _stack(du, dv)


@dataclass(frozen=True)
class ExtrusionSurface(_Surface):
    """``profile`` (parameter ``u``) moved by ``v`` along the unit ``direction`` (3,)."""

    profile: Profile
    direction: FloatArray

    def evaluate(self, p: FloatArray) -> FloatArray:
        u, v = _p(p)
        return self.profile.evaluate(u) + v[:, None] * self.direction

    def jacobian(self, p: FloatArray) -> FloatArray:
        u, _ = _p(p)
        _, dc = self.profile.jet(u)
        return _stack(dc, np.broadcast_to(self.direction, (len(u), 3)))


# ---- NURBS --------------------------------------------------------------------------------
def basis_and_derivative(
    knots: FloatArray, degree: int, t: FloatArray, extrapolate: bool = False
) -> tuple[np.ndarray, FloatArray, FloatArray]:
    """Non-zero B-spline basis functions and their first derivatives at ``t`` (n,).

    ``knots`` is the full (clamped or not) knot vector with repeated entries. Returns the
    span index (n,) ``i`` (functions ``N_{i-p..i}`` are non-zero), values (n, p+1) and
    derivatives (n, p+1). Cox-de Boor (The NURBS Book, A2.2 and A2.3), compiled
    (``medax.geometry.basis_kernel.basis_point``). Outside
    the domain ``t`` is clamped to it, or with ``extrapolate`` the end spans' polynomials
    are continued.
    """
    kn = np.ascontiguousarray(knots, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    p = int(degree)
    kernels.announce_compile()
    no_polynomials = np.zeros((0, p + 1, p + 1))  # (Cox-de Boor)
    span, values, ders = span_basis_rows(kn, no_polynomials, p, bool(extrapolate), t.ravel())
    return span.reshape(t.shape), values, ders


@dataclass(frozen=True)
class SpanBasis:
    """The non-zero B-spline basis functions of one knot vector as polynomials per span:
    evaluating them is a gather and a small product, not the Cox-de Boor recursion (which
    was most of the freeform fitted merge's time).

    ``coef[s]`` (p+1, p+1) maps the powers ``tau^j`` of the span's local coordinate
    ``tau = (t - knots[s]) / (knots[s+1] - knots[s])`` to the values of ``N_{s-p..s}``;
    built once by solving the recursion's values at ``p + 1`` points inside each span.
    """

    knots: FloatArray
    degree: int
    extrapolate: bool
    coef: FloatArray
    lo: float
    hi: float

    @classmethod
    def of(cls, knots: FloatArray, degree: int, extrapolate: bool = False) -> SpanBasis:
        kn = np.ascontiguousarray(knots, dtype=np.float64)
        p = int(degree)
        n_ctrl = kn.size - 1 - p
        coef = np.zeros((kn.size - 1, p + 1, p + 1))
        tau = (np.arange(p + 1) + 0.5) / (p + 1)  # inside the span: the recursion's span is s
        vander = np.vander(tau, p + 1, increasing=True)  # (samples, powers)
        spans = np.arange(p, n_ctrl)
        spans = spans[kn[spans + 1] > kn[spans]]
        if spans.size:  # every span's samples in one recursion, one batched solve
            a, b = kn[spans][:, None], kn[spans + 1][:, None]
            _, vals, _ = basis_and_derivative(kn, p, (a + tau[None, :] * (b - a)).ravel())
            sol = np.linalg.solve(vander[None], vals.reshape(spans.size, p + 1, p + 1))
            coef[spans] = np.swapaxes(sol, 1, 2)  # (span, function, power)
        return cls(kn, p, extrapolate, coef, float(kn[p]), float(kn[n_ctrl]))

    @property
    def kernel_args(self) -> tuple[FloatArray, FloatArray, int, bool]:
        """The arguments ``kn, coef, p, extrapolate`` of
        :func:`medax.geometry.basis_kernel.basis_at`: the power basis up to
        :data:`~medax.geometry.bspline.POWER_BASIS_MAX_DEGREE`, Cox-de Boor above it (an
        empty ``coef``; the power basis of a high degree loses digits: a degree-13 fillet
        blend had 1e-9 noise in its points, and Newton on them stalled there)."""
        p = self.degree
        coef = self.coef if p <= POWER_BASIS_MAX_DEGREE else np.zeros((0, p + 1, p + 1))
        return (self.knots, coef, p, bool(self.extrapolate))

    def __call__(self, t: FloatArray) -> tuple[np.ndarray, FloatArray, FloatArray]:
        """Span index (n,), values (n, p+1) and first derivatives (n, p+1) at ``t`` (n,),
        as :func:`basis_and_derivative` (compiled: ``basis_kernel.span_basis_rows``)."""
        kernels.announce_compile()
        t = np.asarray(t, dtype=np.float64).reshape(-1)
        span, values, ders = span_basis_rows(*self.kernel_args, t)
        return span, values, ders


#: Points per chunk of a NURBS evaluation (see ``NurbsSurface._jet``).
PARTS_CHUNK = 32768


@dataclass(frozen=True)
class NurbsSurface(_Surface):
    """Tensor-product NURBS surface on its own knot domain (OCCT's parameters).

    ``poles`` (nu, nv, 3); ``weights`` (nu, nv) positive or None (polynomial); ``uknots``
    and ``vknots`` full knot vectors with repeats, lengths ``nu + udeg + 1`` and
    ``nv + vdeg + 1``. With ``extrapolate`` the surface is continued past its domain (the
    end spans' polynomials), else parameters are clamped to it.
    """

    poles: FloatArray
    udeg: int
    vdeg: int
    uknots: FloatArray
    vknots: FloatArray
    weights: FloatArray | None = None
    extrapolate: bool = False
    _hom: FloatArray = field(init=False, repr=False, compare=False)
    _ubasis: SpanBasis = field(init=False, repr=False, compare=False)
    _vbasis: SpanBasis = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        poles = np.asarray(self.poles, dtype=np.float64)
        nu, nv = poles.shape[:2]
        if poles.ndim != 3 or poles.shape[2] != 3:
            raise InputError(f"NURBS poles must be (nu, nv, 3), got {poles.shape}")
        if len(self.uknots) != nu + self.udeg + 1 or len(self.vknots) != nv + self.vdeg + 1:
            raise InputError("NURBS knot vectors must have n + degree + 1 entries")
        w = np.ones((nu, nv)) if self.weights is None else np.asarray(self.weights, float)
        if w.shape != (nu, nv) or np.any(w <= 0.0):
            raise InputError("NURBS weights must be positive, shape (nu, nv)")
        hom = np.concatenate((poles * w[:, :, None], w[:, :, None]), axis=2)
        object.__setattr__(self, "_hom", hom)
        object.__setattr__(self, "_ubasis", SpanBasis.of(self.uknots, self.udeg, self.extrapolate))
        object.__setattr__(self, "_vbasis", SpanBasis.of(self.vknots, self.vdeg, self.extrapolate))

    @property
    def kernel_args(
        self,
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, bool]:
        """The surface arguments ``hom, ukn, ucoef, vkn, vcoef, extrapolate`` of
        :mod:`medax.geometry.nurbs_kernel`: homogeneous poles (nu, nv, 4), both directions'
        knots and span polynomials (:attr:`SpanBasis.kernel_args`)."""
        ukn, ucoef, _, _ = self._ubasis.kernel_args
        vkn, vcoef, _, _ = self._vbasis.kernel_args
        return (self._hom, ukn, ucoef, vkn, vcoef, bool(self.extrapolate))

    def _jet(self, p: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        a = points2d(p)
        kernels.announce_compile()
        if len(a) > PARTS_CHUNK:
            # in chunks (the compiled jet keeps no per-point temporaries; the chunks only
            # bound one call's run between interrupt checks)
            out = tuple(np.empty((len(a), 3)) for _ in range(3))
            for k in range(0, len(a), PARTS_CHUNK):
                for o, r in zip(out, self._jet(a[k : k + PARTS_CHUNK]), strict=True):
                    o[k : k + PARTS_CHUNK] = r
            return out[0], out[1], out[2]
        x, du, dv = jet_rows(*self.kernel_args, np.ascontiguousarray(a[:, :2]))
        return x, du, dv

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(u0, u1, v0, v1) of the knot domain."""
        u, v, pu, pv = self.uknots, self.vknots, self.udeg, self.vdeg
        return float(u[pu]), float(u[len(u) - pu - 1]), float(v[pv]), float(v[len(v) - pv - 1])

    def evaluate(self, p: FloatArray) -> FloatArray:
        return self._jet(p)[0]

    def jet(self, p: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Points, d/du and d/dv at ``p`` (n, 2): three (n, 3) arrays, compiled
        (:func:`medax.geometry.nurbs_kernel.jet_rows`)."""
        return self._jet(p)

    def jacobian(self, p: FloatArray) -> FloatArray:
        _, du, dv = self.jet(p)
        return _stack(du, dv)
