"""Tabulated inverse of the body model: a starting point for the survey matcher.

anny's measures are not monotone in its parameters: at a given weight, mass and waist are
*lowest* near muscle 0.5 and grow towards both muscle 0 (fat) and muscle 1 (muscular). A
gradient fit started at the neutral body therefore stalls on the wrong side for many real
people. The table picks the right basin before the fit starts:

* a *shape* table: for each sex and each age node, a grid of (muscle, weight, proportions)
  at height 0.5 and a neutral ethnic mix, with its scale-free measures
  BMI, waist / stature and hip / stature;
* a *stature* table: for each sex and age node, stature at a few heights (other parameters 0.5).

For a person, both tables are interpolated linearly in anny's age parameter between the two
nearest age nodes; the shape cell nearest to the person's BMI and girth ratios (distances in
units of the match tolerances at the person's stature) gives muscle, weight and proportions,
and the stature table, scaled by that cell's stature relative to the neutral body and inverted
by linear interpolation, gives height. A start can be restricted to one side of muscle 0.5, so
that a fit that ends in the wrong basin can be tried again from the other.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from wbsa.bodies.age import years_to_param
from wbsa.bodies.body_model import PHENOTYPE_COLUMNS
from wbsa.bodies.survey_measures import TorchMeasurer

_INDEX = {name: i for i, name in enumerate(PHENOTYPE_COLUMNS)}


@dataclass(frozen=True)
class StartGrid:
    """The bodies of a :class:`StartTable`.

    Attributes
    ----------
    age_nodes_years
        Age nodes, increasing (ages outside take the nearest node).
    muscle, weight, proportions
        Values of the shape table's grid.
    heights
        Heights of the stature table, increasing; must include 0.5.
    """

    age_nodes_years: tuple[float, ...] = (2.0, 4.0, 6.0, 9.0, 12.0, 15.0, 18.0, 30.0, 50.0, 70.0, 90.0)
    muscle: tuple[float, ...] = (0.0, 0.2, 0.5, 0.8, 1.0)
    weight: tuple[float, ...] = (0.0, 0.25, 0.5, 0.75, 0.9, 1.0)
    proportions: tuple[float, ...] = (0.2, 0.8)
    heights: tuple[float, ...] = (0.0, 0.25, 0.5, 0.75, 1.0)

    def __post_init__(self) -> None:
        from wbsa.errors import WbsaError
        from wbsa.settings_io import check_types

        check_types(self)
        if len(self.age_nodes_years) < 2 or np.any(np.diff(self.age_nodes_years) <= 0):
            raise WbsaError("start grid age nodes must be at least two increasing ages")
        if 0.5 not in self.heights or np.any(np.diff(self.heights) <= 0):
            raise WbsaError("start grid heights must increase and include 0.5")

    @property
    def size(self) -> int:
        """Bodies in the table."""
        shape = len(self.muscle) * len(self.weight) * len(self.proportions)
        return 2 * len(self.age_nodes_years) * (shape + len(self.heights))


@dataclass(frozen=True)
class StartTable:
    """Measures of a fixed grid of bodies, for starting the fit.

    Attributes
    ----------
    grid : StartGrid
        The tabulated bodies.
    age_nodes : (a,) float64
        anny age parameter of each node.
    shape_params : (c, 3) float64
        (muscle, weight, proportions) of each shape cell.
    shape : (2, a, c, 4) float64
        BMI, waist / stature, hip / stature and stature relative to the neutral body of the
        stature table at height 0.5, per sex (0 male, 1 female), age node and cell.
    stature : (2, a, h) float64
        Stature (m) per sex, age node and height of ``grid.heights``.
    """

    grid: StartGrid
    age_nodes: np.ndarray
    shape_params: np.ndarray
    shape: np.ndarray
    stature: np.ndarray

    @classmethod
    def build(cls, measurer: TorchMeasurer, grid: StartGrid = StartGrid(), batch_size: int = 256) -> "StartTable":
        """Measure every table body with ``measurer`` (``grid.size`` bodies, 1,430 by default)."""
        ages = years_to_param(np.array(grid.age_nodes_years))
        cells = np.array([(m, w, p) for m in grid.muscle for w in grid.weight for p in grid.proportions])
        rows, stature_rows = [], []
        for sex in (0.0, 1.0):
            for age in ages:
                for m, w, p in cells:
                    rows.append(_phenotypes(sex, age, muscle=m, weight=w, proportions=p))
                for h in grid.heights:
                    stature_rows.append(_phenotypes(sex, age, height=h))
        shape_values = _measure(measurer, np.array(rows), batch_size)
        stature_values = _measure(measurer, np.array(stature_rows), batch_size)
        stature = stature_values[:, 0].reshape(2, len(ages), len(grid.heights))
        neutral = stature[:, :, grid.heights.index(0.5)]
        st = shape_values[:, 0]
        shape = np.stack([shape_values[:, 1] / st**2, shape_values[:, 2] / st, shape_values[:, 3] / st,
                          st], axis=1).reshape(2, len(ages), len(cells), 4)
        shape[..., 3] /= neutral[:, :, None]
        return cls(grid=grid, age_nodes=ages, shape_params=cells, shape=shape, stature=stature)

    def start(self, fixed: np.ndarray, goal: np.ndarray, tolerances: np.ndarray,
              muscle_side: Literal["any", "low", "high"] = "any") -> np.ndarray:
        """Starting (muscle, weight, height, proportions) ``(b, 4)`` of each person.

        Parameters
        ----------
        fixed : (b, 5) float64
            p_gender, p_age, p_african, p_asian, p_caucasian.
        goal : (b, 4) float64
            Target stature (m), mass (kg), waist and hip (m); NaN girths are ignored.
        tolerances : (4,) float64
            Match tolerances, the units of the table distance.
        muscle_side
            Only cells with muscle <= 0.5 (``low``) or >= 0.5 (``high``): the two basins of
            anny's muscle, for a second start on the other side.
        """
        sex = (fixed[:, 0] >= 0.5).astype(int)
        lo, w = _age_weights(self.age_nodes, fixed[:, 1])
        shape = (1 - w)[:, None, None] * self.shape[sex, lo] + w[:, None, None] * self.shape[sex, lo + 1]
        stature = (1 - w)[:, None] * self.stature[sex, lo] + w[:, None] * self.stature[sex, lo + 1]
        h = goal[:, 0]
        # person's measures in the table's scale-free units, and tolerances in the same units
        target = np.stack([goal[:, 1] / h**2, goal[:, 2] / h, goal[:, 3] / h], axis=1)
        scale = np.stack([tolerances[1] / h**2, tolerances[2] / h, tolerances[3] / h], axis=1)
        diff = (shape[..., :3] - target[:, None, :]) / scale[:, None, :]
        diff = np.where(np.isfinite(target)[:, None, :], diff, 0.0)
        cost = (diff**2).sum(axis=2)
        if muscle_side != "any":
            m = self.shape_params[:, 0]
            cost = np.where((m <= 0.5) if muscle_side == "low" else (m >= 0.5), cost, np.inf)
        best = np.argmin(cost, axis=1)
        muscle, weight, proportions = self.shape_params[best].T
        # the chosen cell is taller or shorter than the neutral body by a factor; heights scale with it
        factor = shape[np.arange(len(h)), best, 3]
        heights = np.array(self.grid.heights)
        height = np.array([_invert(stature[i] * factor[i], h[i], heights) for i in range(len(h))])
        return np.stack([muscle, weight, height, proportions], axis=1)


def _phenotypes(sex: float, age: float, **free: float) -> np.ndarray:
    row = np.full(len(PHENOTYPE_COLUMNS), 0.5)
    row[_INDEX["p_gender"]] = sex
    row[_INDEX["p_age"]] = age
    row[[_INDEX["p_african"], _INDEX["p_asian"], _INDEX["p_caucasian"]]] = 1.0 / 3.0
    for name, value in free.items():
        row[_INDEX[f"p_{name}"]] = value
    return row


def _measure(measurer: TorchMeasurer, phenotypes: np.ndarray, batch_size: int) -> np.ndarray:
    torch = measurer.torch
    out = []
    for start in range(0, len(phenotypes), batch_size):
        ph = torch.as_tensor(phenotypes[start:start + batch_size], dtype=measurer.dtype)
        with torch.no_grad():
            out.append(measurer.evaluate(measurer.vertices(measurer.coefficients(ph)), trunk_only=True).values.numpy())
    return np.concatenate(out)


def _age_weights(nodes: np.ndarray, age: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lower node index ``(b,)`` and interpolation weight ``(b,)`` in [0, 1] of each age."""
    a = np.clip(age, nodes[0], nodes[-1])
    lo = np.clip(np.searchsorted(nodes, a, side="right") - 1, 0, len(nodes) - 2)
    w = (a - nodes[lo]) / (nodes[lo + 1] - nodes[lo])
    return lo, np.clip(w, 0.0, 1.0)


def _invert(stature: np.ndarray, target: float, heights: np.ndarray) -> float:
    """Height parameter whose (interpolated) stature is ``target``, clipped to the grid."""
    order = np.argsort(stature)
    return float(np.interp(target, stature[order], heights[order]))
