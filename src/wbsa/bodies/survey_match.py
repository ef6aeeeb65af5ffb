"""Fit anny phenotypes to body measures: stature, mass, waist, hip, arm and leg of real people.

(About 540 lines, above the project's ~400: the batched Levenberg–Marquardt solver, its bounds, step
control and the girth rescue share one set of per-person state arrays; splitting them would pass that
state across modules for no gain in clarity.)

Each person keeps the fixed parameters it is given (gender, age, ethnic mix) and the free
ones (muscle, weight, height, proportions, the trunk's four local changes — waist, hips, belly,
buttocks —, with seven measures the limbs' three — upper-arm girth and length, upper-leg length —
and cup size for women) are fitted so that the body's stature, mass, waist and hip, and with
``measures = "seven"`` its NHANES arm circumference, upper arm length and upper leg length (as
:class:`~wbsa.bodies.anthropometry.Anthropometer` defines them), equal the person's. The fit is a damped Gauss–Newton (Levenberg–Marquardt)
least-squares problem per person, solved for a whole batch at once:

* unknowns: the free phenotypes themselves, and each local change ``l`` as ``(l + 1) / 2``
  (so that every unknown lives in [0, 1] and 0.5 is the neutral value), kept inside
  ``bounds`` by projection: a step is
  clipped to the box, and a parameter on a bound that the gradient pushes outwards sits out
  the step (a sigmoid map would do the same job but traps parameters that reach a bound,
  where its slope vanishes);
* residuals: ``(measure − target) / tolerance`` for every measure the person has (a missing
  waist or hip simply drops out), weighted by ``weights`` so that stature and mass come
  first, plus a weak pull of each free parameter towards 0.5 (``prior_weight``) that picks
  the most neutral body when several fit equally well;
* Jacobian: exact, from :class:`~wbsa.bodies.survey_measures.TorchMeasurer` (measure
  gradients in blendshape space) chained through anny's phenotype → coefficient map;
* start: a tabulated inverse (:class:`~wbsa.bodies.survey_start.StartTable`), which puts
  every person in the right basin (anny's mass and waist are not monotone in muscle).

A person leaves the batch once every measure it has is within ``converge_fraction`` of its
tolerance, after ``_STALL`` iterations without progress, or after ``max_iterations``. Each
person's steps depend on that person only, so results do not depend on the batch size or on
who else is in the batch (up to floating-point rounding of the batched products).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from wbsa.errors import WbsaError
from wbsa.bodies.body_model import ALL_LOCAL_CHANGE_COLUMNS, BODY_PARAMETER_COLUMNS, LIMB_CHANGE_COLUMNS
from wbsa.bodies.survey_measures import TorchMeasurer, fit_measures
from wbsa.typing import SurveyMeasures
from wbsa.bodies.survey_start import StartGrid, StartTable
from wbsa.parallel import torch_threads
from wbsa.progress import progress
from wbsa.settings_io import check_types

#: Target columns :func:`match_bodies` reads (NaN waist, hip or limb measure = not measured), in the order
#: of :data:`~wbsa.bodies.survey_measures.FIT_MEASURES`; the last three only with seven measures.
TARGET_COLUMNS = ("target_stature_m", "target_mass_kg", "target_waist_circ_m", "target_hip_circ_m",
                  "target_mid_arm_circ_m", "target_upper_arm_length_m", "target_upper_leg_length_m")
#: Optional target column: each person's body density (kg/m³) for mass = volume × density
#: (absent: the measurer's one density).
DENSITY_COLUMN = "target_density_kg_m3"
#: Fixed phenotype columns :func:`match_bodies` reads.
FIXED_COLUMNS = ("p_gender", "p_age", "p_african", "p_asian", "p_caucasian")
#: Free body parameters, in fit order (``p_cupsize`` only for women, the ``l_*`` local changes
#: unless switched off, the limbs' only with seven measures, see :class:`MatchSettings`). The first
#: four come from the start table.
FREE_PHENOTYPES = ("p_muscle", "p_weight", "p_height", "p_proportions", *ALL_LOCAL_CHANGE_COLUMNS, "p_cupsize")

_INDEX = {name: i for i, name in enumerate(BODY_PARAMETER_COLUMNS)}
#: positions in FREE_PHENOTYPES of the local changes (their unknown is (l + 1) / 2)
_LOCAL = [FREE_PHENOTYPES.index(c) for c in ALL_LOCAL_CHANGE_COLUMNS]
_LIMB = [FREE_PHENOTYPES.index(c) for c in LIMB_CHANGE_COLUMNS]
_STALL = 5
_DAMPING_FLOOR = 1e-3
_KINK_HOP = 1e-5


@dataclass(frozen=True)
class MatchSettings:
    """How bodies are fitted to survey measures.

    Attributes
    ----------
    measures
        ``seven`` (default): stature, mass, waist, hip and the NHANES arm circumference, upper arm
        length and upper leg length, with the limbs' local changes free; ``four``: the first four,
        the limbs' local changes kept at 0 (the matcher's bodies before the limb measures).
    stature_tol_m, mass_tol_kg, girth_tol_m, arm_circ_tol_m, limb_length_tol_m
        Match tolerances (1 cm, 1 kg, 3 cm for waist and hip, 2 cm for the arm circumference, 1.5 cm
        for the arm and leg lengths): a body matches when every measured quantity is within them;
        residuals are scaled by them, so they also weigh the least squares.
    bounds
        ``(low, high)`` range of every free phenotype.
    free_cupsize
        Fit cup size for women (men keep 0.5, where it has almost no effect).
    free_local_changes
        Fit the body model's local changes (waist, hips, belly, buttocks; otherwise they stay
        0). With phenotypes alone anny cannot reach most real waist–hip combinations.
    weights
        Weights of the stature, mass, waist, hip, arm circumference, arm length and leg length
        residuals (each in units of its tolerance; with four measures the first four are used). Stature and mass are met first and the girths fitted as well as the body
        model allows with them held (anny cannot reach every real waist–hip combination at a
        given stature and mass); where even the mass is out of reach (BMI beyond anny's range)
        stature weighs more, so the body keeps the person's stature and falls short in mass
        rather than growing taller to gain it.
    prior_weight
        Weight of the pull of each free phenotype towards 0.5 (in tolerance units per unit
        of phenotype).
    rescue_weights
        None, or the residual weights of a second fit for the people whose stature and mass
        are matched but a girth is not: weighted as above, the fit meets the mass to a few
        grams and leaves the girths off where anny cannot reach both (heavy women at weight 1,
        muscle 0); with the mass weighted like a girth, the second fit may use the mass
        tolerance to bring the girths in. Its result is kept only where all four measures are
        then within tolerance (the first fit's otherwise).
    max_iterations
        Levenberg–Marquardt iterations per person at most.
    converge_fraction
        A person is done when every error is below this fraction of its tolerance.
    batch_size
        People fitted together.
    start
        The bodies of the tabulated inverse that starts every fit.
    threads
        torch intra-op threads while fitting (None: leave torch's setting). The fit is many
        small operations, for which one thread is fastest (on the 2-core build machine two
        threads took 2.4 times the CPU time and twice the wall time); a fixed count also
        makes the results bitwise independent of the machine's core count.
    """

    measures: SurveyMeasures = "seven"
    stature_tol_m: float = 0.01
    mass_tol_kg: float = 1.0
    girth_tol_m: float = 0.03
    arm_circ_tol_m: float = 0.02
    limb_length_tol_m: float = 0.015
    bounds: tuple[float, float] = (0.0, 1.0)
    free_cupsize: bool = True
    free_local_changes: bool = True
    weights: tuple[float, ...] = (3.0, 1.0, 0.1, 0.1, 0.1, 0.1, 0.1)
    prior_weight: float = 0.05
    rescue_weights: tuple[float, ...] | None = None
    max_iterations: int = 40
    converge_fraction: float = 0.25
    batch_size: int = 256
    start: StartGrid = field(default_factory=StartGrid)
    threads: int | None = 1

    def __post_init__(self) -> None:
        check_types(self)
        lo, hi = self.bounds
        if not 0.0 <= lo < hi <= 1.0:
            raise WbsaError(f"match bounds {self.bounds} must satisfy 0 <= low < high <= 1")
        for name in ("stature_tol_m", "mass_tol_kg", "girth_tol_m", "arm_circ_tol_m", "limb_length_tol_m"):
            if not getattr(self, name) > 0:
                raise WbsaError(f"match tolerance {name} = {getattr(self, name)} must be positive")
        for name in ("weights", "rescue_weights"):
            w = getattr(self, name)
            if w is not None and (len(w) != 7 or not all(x > 0 for x in w)):
                raise WbsaError(f"match {name} {w} must be seven positive numbers (stature, mass, waist, hip, "
                                "arm circumference, arm length, leg length)")
        if self.threads is not None and self.threads < 1:
            raise WbsaError(f"match threads = {self.threads} must be >= 1 (or None for torch's default)")
        if self.max_iterations < 0 or self.batch_size < 1:
            raise WbsaError("match max_iterations must be >= 0 and batch_size >= 1")

    @property
    def names(self) -> tuple[str, ...]:
        """The matched measures (:func:`~wbsa.bodies.survey_measures.fit_measures`)."""
        return fit_measures(self.measures)

    @property
    def tolerances(self) -> np.ndarray:
        """(m,) tolerances of :attr:`names`, m = 4 or 7."""
        tol = np.array([self.stature_tol_m, self.mass_tol_kg, self.girth_tol_m, self.girth_tol_m, self.arm_circ_tol_m,
                        self.limb_length_tol_m, self.limb_length_tol_m])
        return tol[:len(self.names)]

    @property
    def tolerance_of(self) -> dict[str, float]:
        """Tolerance of every measure (all seven, SI units), by measure name."""
        names = fit_measures("seven")
        tol = replace(self, measures="seven").tolerances
        return dict(zip(names, tol.tolist()))


def match_bodies(targets: pd.DataFrame, measurer: TorchMeasurer, settings: MatchSettings = MatchSettings(), *,
                 table: StartTable | None = None, show_progress: bool | None = None) -> pd.DataFrame:
    """Fit the free body parameters of every row of ``targets`` to its measures.

    Parameters
    ----------
    targets
        :data:`FIXED_COLUMNS` (in [0, 1]) and :data:`TARGET_COLUMNS` (SI units; the first four, or
        all seven with ``settings.measures = "seven"``; every one but stature and mass may be NaN,
        stature and mass must be finite and positive), optionally :data:`DENSITY_COLUMN`, the
        density each person's mass is computed with.
    measurer
        Differentiable measures of the body model, of the same measures as ``settings``.
    settings
        Tolerances, bounds and iteration limits.
    table
        The tabulated inverse that gives each person's start; built here from
        ``settings.start`` when omitted.

    Returns
    -------
    pandas.DataFrame
        One row per target, same index order: every ``p_*`` and ``l_*`` column
        (:data:`~wbsa.bodies.body_model.BODY_PARAMETER_COLUMNS`), ``fit_<measure>`` (the
        fitted body's measures as the fit saw them, SI), ``fit_iterations`` and
        ``fit_converged`` (every measured quantity within ``converge_fraction`` of its tolerance).
    """
    m = len(settings.names)
    if measurer.names != settings.names:
        raise WbsaError(f"the measurer measures {len(measurer.names)} quantities, the match settings {m}; "
                        f"build TorchMeasurer(..., measures={settings.measures!r})")
    missing = [c for c in (*FIXED_COLUMNS, *TARGET_COLUMNS[:m]) if c not in targets.columns]
    if missing:
        raise WbsaError(f"match targets lack columns {missing}")
    fixed = targets[list(FIXED_COLUMNS)].to_numpy(dtype=np.float64)
    goal = targets[list(TARGET_COLUMNS[:m])].to_numpy(dtype=np.float64)
    if not (np.isfinite(goal[:, :2]).all() and (goal[:, :2] > 0).all()):
        raise WbsaError("every match target needs a finite, positive stature and mass")
    n = len(targets)
    if DENSITY_COLUMN in targets.columns:
        density = targets[DENSITY_COLUMN].to_numpy(dtype=np.float64)
        if not (np.isfinite(density).all() and (density > 0).all()):
            raise WbsaError(f"{DENSITY_COLUMN} must be finite and positive for every match target")
    else:
        density = np.full(n, measurer.density_kg_m3)
    phen = np.zeros((n, len(BODY_PARAMETER_COLUMNS)))
    fit = np.full((n, m), np.nan)
    iters = np.zeros(n, dtype=np.int64)
    done = np.zeros(n, dtype=bool)
    with torch_threads(settings.threads):
        table = table if table is not None else StartTable.build(measurer, settings.start)
        with progress(total=n, desc="matching", unit="person", enabled=show_progress) as bar:
            for start in range(0, n, settings.batch_size):
                sl = slice(start, start + settings.batch_size)
                phen[sl], fit[sl], iters[sl], done[sl] = _match_batch(fixed[sl], goal[sl], density[sl], measurer,
                                                                      settings, table)
                bar.update(len(fixed[sl]))
    out = pd.DataFrame(phen, columns=list(BODY_PARAMETER_COLUMNS), index=targets.index)
    for j, name in enumerate(settings.names):
        out[f"fit_{name}"] = fit[:, j]
    out["fit_iterations"] = iters
    out["fit_converged"] = done
    return out


# -- the fit ---------------------------------------------------------------------------------
class _Problem:
    """One batch: fixed phenotypes, targets, and the map from unknowns to residuals."""

    def __init__(self, fixed: np.ndarray, goal: np.ndarray, density: np.ndarray, measurer: TorchMeasurer,
                 settings: MatchSettings):
        import torch

        self.torch = torch
        self.m = measurer
        self.s = settings
        b = len(fixed)
        base = np.full((b, len(BODY_PARAMETER_COLUMNS)), 0.5)
        for j, name in enumerate(FIXED_COLUMNS):
            base[:, _INDEX[name]] = fixed[:, j]
        self.base = torch.as_tensor(base, dtype=measurer.dtype)
        self.free_index = [_INDEX[c] for c in FREE_PHENOTYPES]
        # (b, d) mask of the unknowns each person really has (cup size: women only)
        mask = np.ones((b, len(FREE_PHENOTYPES)), dtype=bool)
        mask[:, _LOCAL] = settings.free_local_changes
        if settings.measures == "four":
            mask[:, _LIMB] = False
        if not settings.free_cupsize:
            mask[:, -1] = False
        else:
            mask[:, -1] = fixed[:, 0] >= 0.5
        self.free_mask = torch.as_tensor(mask)
        # (unknown index, value) of every inner interpolation anchor of a free phenotype
        lo, hi = settings.bounds
        self.kinks = []
        for j, name in enumerate(FREE_PHENOTYPES):
            # a local change switches from its decr to its incr target at 0 (unknown 0.5)
            anchors = [0.5] if j in _LOCAL else measurer.model.anny.anchors[name[2:]][1:-1].tolist()
            for a in anchors:
                if lo < a < hi:
                    self.kinks.append((j, float(a)))
        self.goal = torch.as_tensor(np.nan_to_num(goal, nan=0.0), dtype=measurer.dtype)
        self.has = torch.as_tensor(np.isfinite(goal))
        #: (b,) each person's body density, kg/m³
        self.density = torch.as_tensor(np.array(density, dtype=np.float64), dtype=measurer.dtype)
        self.tol = torch.as_tensor(settings.tolerances, dtype=measurer.dtype)
        weight = np.asarray(settings.weights, dtype=np.float64)
        #: residual unit of each measure: its tolerance over its weight
        self.unit = self.tol / torch.as_tensor(weight[:len(settings.tolerances)], dtype=measurer.dtype)
        self.n_measures = len(settings.tolerances)

    def phenotypes(self, u):
        """(b, 15) body parameters and (b, d) free values for unknowns ``u`` (b, d) (differentiable)."""
        return _SubProblem(self, slice(None)).phenotypes(u)

    def stop_at_kinks(self, u, step):
        """``u + step``, cut short just past the first interpolation anchor the step crosses.

        anny interpolates each phenotype linearly between anchors (0, 0.5, 1 for muscle,
        weight and cup size), so the measures have a kink at every inner anchor. A Gauss–Newton
        step that crosses one is based on the slope of the wrong side; stopping just beyond
        it lets the next step use the new side's slope.
        """
        torch = self.torch
        alpha = torch.ones(len(u), dtype=u.dtype)
        for j, kink in self.kinks:
            crossing = (u[:, j] - kink) * (u[:, j] + step[:, j] - kink) < 0
            frac = (kink - u[:, j]) / torch.where(crossing, step[:, j], torch.ones_like(step[:, j]))
            alpha = torch.where(crossing & (frac < alpha), frac, alpha)
        trial = u + alpha[:, None] * step
        for j, kink in self.kinks:
            landed = (alpha < 1) & ((trial[:, j] - kink).abs() <= 1e-12 + 1e-9 * step[:, j].abs())
            trial[:, j] = torch.where(landed, kink + _KINK_HOP * torch.sign(step[:, j]), trial[:, j])
        lo, hi = self.s.bounds
        return trial.clamp(lo, hi)

    def pinned_at_kinks(self, u, step):
        """(b, d) bool: unknowns sitting at an interpolation anchor that ``step`` would carry across.

        A parameter at the bottom of a kink (anny's mass is lowest at muscle 0.5) gets steps
        that cross the anchor back and forth; cutting every
        such step at the anchor would freeze all the other unknowns too. Such a parameter is
        held at the anchor for the step instead, and the others move.
        """
        torch = self.torch
        pinned = torch.zeros_like(u, dtype=torch.bool)
        for j, kink in self.kinks:
            near = (u[:, j] - kink).abs() <= 2 * _KINK_HOP
            crossing = (u[:, j] - kink) * (u[:, j] + step[:, j] - kink) < 0
            pinned[:, j] |= near & crossing
        return pinned

    def residuals(self, u, rows, jacobian: bool):
        """Residuals ``(b, m + d)``, measures ``(b, m)``, Jacobian ``(b, m + d, d)`` at free values ``u`` of ``rows``."""
        torch = self.torch
        sub = _SubProblem(self, rows)
        uu = u.detach().clone().requires_grad_(jacobian)
        with torch.set_grad_enabled(jacobian):
            ph, free = sub.phenotypes(uu)
            coeffs = self.m.coefficients(ph)
        ev = self.m.evaluate(self.m.vertices(coeffs), gradient=jacobian, density_kg_m3=sub.density,
                             coefficients=coeffs.detach())
        values = ev.values
        has = sub.has & torch.isfinite(values)
        err = torch.where(has, (values - sub.goal) / self.unit, torch.zeros_like(values))
        prior = self.s.prior_weight * (free.detach() - 0.5) * sub.free_mask
        r = torch.cat([err, prior], dim=1)
        if not jacobian:
            return r, values, None
        d, m = u.shape[1], self.n_measures
        jac = torch.zeros((len(rows), m + d, d), dtype=u.dtype)
        for k in range(m):
            weight = torch.where(has[:, k:k + 1], ev.grad[:, k] / self.unit[k], torch.zeros_like(ev.grad[:, k]))
            (g,) = torch.autograd.grad(coeffs, uu, grad_outputs=weight, retain_graph=True)
            jac[:, k] = g
        jac[:, m:] = torch.diag_embed(self.s.prior_weight * sub.free_mask.to(u.dtype))
        jac = jac * sub.free_mask[:, None, :]
        return r, values, jac


class _SubProblem:
    """The rows ``rows`` of a :class:`_Problem`."""

    def __init__(self, p: _Problem, rows):
        self.p = p
        self.base = p.base[rows]
        self.free_mask = p.free_mask[rows]
        self.goal = p.goal[rows]
        self.has = p.has[rows]
        self.density = p.density[rows]

    def phenotypes(self, u):
        torch = self.p.torch
        free = torch.where(self.free_mask, u, torch.full_like(u, 0.5))
        value = free.clone()
        value[:, _LOCAL] = 2.0 * free[:, _LOCAL] - 1.0
        ph = self.base.clone()
        ph[:, self.p.free_index] = value
        return ph, free


def _start(problem: _Problem, table: StartTable, fixed: np.ndarray, goal: np.ndarray, density: np.ndarray,
           muscle_side: str = "any") -> np.ndarray:
    """Starting unknowns ``(b, d)`` from the tabulated inverse (cup size at 0.5, no local change).

    The table's bodies were weighed at the measurer's density: a person of another density is
    looked up by the mass its volume would have there.
    """
    free = np.full((len(fixed), len(FREE_PHENOTYPES)), 0.5)
    goal = goal.copy()
    goal[:, 1] *= problem.m.density_kg_m3 / density
    free[:, :4] = table.start(fixed, goal[:, :4], problem.s.tolerances[:4], muscle_side)
    return np.clip(free, *problem.s.bounds)


def _box_step(r, jac, u, mu, free, bounds):
    """Damped Gauss–Newton step ``(b, d)`` that keeps ``u + step`` inside ``bounds``.

    An active-set loop: a parameter on a bound that the descent direction pushes outwards,
    or one whose step would leave the box, is held at the bound and the step is solved again
    for the others, with the held parameters' moves taken into account. Marquardt damping
    ``mu``, with a floor so that a flat direction (cup size for men) gets no step.
    """
    import torch

    lo, hi = bounds
    jtr = (jac.transpose(1, 2) @ r[..., None])[..., 0]
    held = ~free | ((u <= lo) & (jtr > 0)) | ((u >= hi) & (jtr < 0))
    held_step = torch.zeros_like(u)
    step = held_step
    for _ in range(u.shape[1] + 1):
        moving = ~held
        r_adj = r + (jac @ held_step[..., None])[..., 0]
        jm = jac * moving[:, None, :]
        jtj = jm.transpose(1, 2) @ jm
        g = (jm.transpose(1, 2) @ r_adj[..., None])[..., 0]
        diag = torch.diagonal(jtj, dim1=1, dim2=2) + _DAMPING_FLOOR
        a = jtj + torch.diag_embed(mu[:, None] * diag + _DAMPING_FLOOR)
        step = -torch.linalg.solve(a, g) * moving + held_step
        new = u + step
        out = moving & ((new < lo) | (new > hi))
        if not out.any():
            break
        held_step = torch.where(out, new.clamp(lo, hi) - u, held_step)
        held = held | out
    return step


def _match_batch(fixed: np.ndarray, goal: np.ndarray, density: np.ndarray, measurer: TorchMeasurer,
                 s: MatchSettings, table: StartTable):
    """Fit one batch; returns body parameters (b, 18), fit measures (b, m), iterations (b,), converged (b,).

    People whose stature or mass is still off after the first fit are fitted again from the
    best start on the other side of muscle 0.5 (anny's mass has a separate basin on each
    side), and keep the better of the two fits.
    """
    torch = measurer.torch
    problem = _Problem(fixed, goal, density, measurer, s)
    u0 = torch.as_tensor(_start(problem, table, fixed, goal, density), dtype=measurer.dtype)
    u, r, values, iters = _fit(problem, u0, torch.arange(len(fixed)))
    err = (values - problem.goal).abs() / problem.tol
    retry = torch.nonzero((err[:, :2] > 1.0).any(dim=1)).flatten()
    if len(retry):
        rows = retry.numpy()
        low = (u0[retry, FREE_PHENOTYPES.index("p_muscle")] > 0.5).numpy()
        start = np.where(low[:, None],
                         _start(problem, table, fixed[rows], goal[rows], density[rows], "low"),
                         _start(problem, table, fixed[rows], goal[rows], density[rows], "high"))
        u2, r2, values2, iters2 = _fit(problem, torch.as_tensor(start, dtype=measurer.dtype), retry)
        better = (r2**2).sum(dim=1) < (r[retry] ** 2).sum(dim=1)
        keep = retry[better]
        u[keep], r[keep], values[keep] = u2[better], r2[better], values2[better]
        iters[retry] += iters2
    if s.rescue_weights is not None:
        err = (values - problem.goal).abs() / problem.tol
        girth_off = ((err[:, 2:] > 1.0) & problem.has[:, 2:]).any(dim=1)
        rescue = torch.nonzero((err[:, :2] <= 1.0).all(dim=1) & girth_off).flatten()
        if len(rescue):
            second = _Problem(fixed, goal, density, measurer, replace(s, weights=s.rescue_weights))
            u3, _, values3, iters3 = _fit(second, u[rescue], rescue)
            err3 = (values3 - problem.goal[rescue]).abs() / problem.tol
            ok = ((err3 <= 1.0) | ~problem.has[rescue]).all(dim=1)
            u[rescue[ok]], values[rescue[ok]] = u3[ok], values3[ok]
            iters[rescue] += iters3
    ph, _ = problem.phenotypes(u)
    return ph.detach().numpy(), values.numpy(), iters.numpy(), _converged(problem, values).numpy()


def _converged(problem: _Problem, values):
    """(b,) bool: every measure the person has within ``converge_fraction`` of its tolerance."""
    err = (values - problem.goal).abs() / problem.tol
    return ((err <= problem.s.converge_fraction) | ~problem.has).all(dim=1)


def _fit(problem: _Problem, u, rows):
    """Levenberg–Marquardt from free phenotypes ``u`` (b, d) of the people ``rows`` (b,).

    Returns the final free phenotypes, residuals, measures and iteration counts.
    """
    torch = problem.torch
    s = problem.s
    sub = _SubProblem(problem, rows)
    u = u.clone()
    b = len(rows)
    r, values, jac = problem.residuals(u, rows, jacobian=True)
    mu = torch.full((b,), 1e-2, dtype=u.dtype)
    iters = torch.zeros(b, dtype=torch.long)
    stall = torch.zeros(b, dtype=torch.long)

    def converged():
        err = (values - sub.goal).abs() / problem.tol
        return ((err <= s.converge_fraction) | ~sub.has).all(dim=1)

    done = converged()
    for _ in range(s.max_iterations):
        active = torch.nonzero(~done).flatten()
        if len(active) == 0:
            break
        ra, ja, ua, mua = r[active], jac[active], u[active], mu[active]
        free = sub.free_mask[active]
        step = _box_step(ra, ja, ua, mua, free, s.bounds)
        for _ in range(3):
            pinned = problem.pinned_at_kinks(ua, step) & free
            if not pinned.any():
                break
            free = free & ~pinned
            step = _box_step(ra, ja, ua, mua, free, s.bounds)
        trial = problem.stop_at_kinks(ua, step)
        rt, vt, jt = problem.residuals(trial, rows[active], jacobian=True)
        old, new = (ra**2).sum(dim=1), (rt**2).sum(dim=1)
        better = new < old
        mu[active] = torch.where(better, mua / 3.0, mua * 4.0)
        iters[active] += 1
        # a person is at its optimum when for `_STALL` iterations no step has lowered the cost
        # by 0.1 % while moving some measure by 1 % of its tolerance
        moved = ((vt - values[active]).abs() / problem.tol > 0.01).any(dim=1)
        progress_made = better & moved & (old - new > 1e-3 * old + 1e-9)
        stall[active] = torch.where(progress_made, torch.zeros_like(stall[active]), stall[active] + 1)
        acc = active[better]
        u[acc], r[acc], values[acc], jac[acc] = trial[better], rt[better], vt[better], jt[better]
        done = converged() | (stall >= _STALL)
    return u, r, values, iters
