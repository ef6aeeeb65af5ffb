"""The view from the image: elevation from the floor (or the body's axis), azimuth learned from renders.

The elevation is geometry: the angle of the camera above the horizontal through the subject's centre, the
horizontal being the floor (:func:`wbsa.estimation.subject.measure.measure_subject`; the body's long axis when no
floor is seen). The azimuth is learned: bodies are left/right symmetric, so θ and −θ are one view and the
estimator returns ψ = |θ| in [0, 180]. Two boosted-tree models read the view descriptor (depth and width
profiles over height, unchanged by a mirror image): one the angle from the front–back axis,
ψ' = min(ψ, 180 − ψ) in [0, 90], the other the probability that the camera is in front (ψ < 90).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wbsa.estimation.methods.regression.trees import TreeEnsemble
from wbsa.estimation.methods.view import ViewEstimate

#: Elevation uncertainty (standard deviation, degrees) with and without a floor; measured on training
#: renders when a model is fitted and stored with it, these are only the defaults.
ELEVATION_SD_DEG = {"floor": 1.5, "axis": 3.0}


def azimuth_sd_deg(psi_deg, p_front, axis_sd_deg: float) -> np.ndarray:
    """Standard deviation (degrees) of an azimuth estimate ψ̂ of :meth:`ViewModel.predict`.

    That of the two-point mixture (ψ' with probability P(front), 180 − ψ' with 1 − P), ψ' = min(ψ̂, 180 − ψ̂),
    widened by the spread of ψ' (``axis_sd_deg``, from held-out renders).

    Parameters
    ----------
    psi_deg, p_front : (n,) float64
        Folded azimuth estimate (0–180°) and the probability that the camera is in front.
    axis_sd_deg : float
        Held-out standard deviation of ψ' (degrees; :attr:`ViewModel.axis_sd_deg`).

    Returns
    -------
    (n,) float64
    """
    psi = np.asarray(psi_deg, dtype=np.float64)
    axis_deg = np.minimum(psi, 180.0 - psi)
    flip = np.minimum(p_front, 1.0 - np.asarray(p_front, dtype=np.float64))
    return np.sqrt(axis_sd_deg**2 + flip * (1.0 - flip) * (180.0 - 2.0 * axis_deg) ** 2)


@dataclass(frozen=True)
class ViewModel:
    """Azimuth from a view descriptor.

    Attributes
    ----------
    axis : TreeEnsemble
        ψ' (degrees from the front–back axis, 0–90).
    front : TreeEnsemble
        Log-odds that the camera is in front of the subject.
    axis_sd_deg : float
        Standard deviation of ψ' on held-out renders.
    elevation_sd_deg : dict
        ``{"floor": ..., "axis": ...}`` measured on the training renders.
    """

    axis: TreeEnsemble
    front: TreeEnsemble
    axis_sd_deg: float
    elevation_sd_deg: dict

    def __repr__(self) -> str:
        return (f"ViewModel(azimuth from the axis: {len(self.axis.roots)} trees, front/back: {len(self.front.roots)} "
                f"trees; held-out azimuth s.d. {self.axis_sd_deg:.1f}°)")

    def predict(self, descriptors: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """ψ̂ (n,), its standard deviation (n,) and P(front) (n,) of view descriptors (n, d).

        The standard deviation is :func:`azimuth_sd_deg` with this model's ``axis_sd_deg``.

        Parameters
        ----------
        descriptors : (n, d) float64
            View descriptors (:attr:`SubjectMeasures.descriptor`).
        """
        X = np.atleast_2d(np.asarray(descriptors, dtype=np.float64))
        axis_deg = np.clip(self.axis.predict_raw(X), 0.0, 90.0)
        p = 1.0 / (1.0 + np.exp(-self.front.predict_raw(X)))
        psi = np.where(p >= 0.5, axis_deg, 180.0 - axis_deg)
        return psi, azimuth_sd_deg(psi, p, self.axis_sd_deg), p

    def estimate(self, measures) -> ViewEstimate:
        """The view of a measured subject: azimuth from its view descriptor, elevation measured
        (:class:`~wbsa.estimation.subject.measure.SubjectMeasures`), with their spreads.

        Parameters
        ----------
        measures : SubjectMeasures
        """
        psi, sd, p = (float(v[0]) for v in self.predict(measures.descriptor[None]))
        el_sd = self.elevation_sd_deg["floor" if measures.floor_seen else "axis"]
        return ViewEstimate(psi, sd, measures.elevation_deg, el_sd, p)

    def to_arrays(self) -> dict[str, np.ndarray]:
        """Named arrays for a model file."""
        out = {**self.axis.to_arrays("view_axis_"), **self.front.to_arrays("view_front_")}
        out["view_axis_sd_deg"] = np.array([self.axis_sd_deg])
        out["view_elevation_sd_deg"] = np.array([self.elevation_sd_deg["floor"], self.elevation_sd_deg["axis"]])
        return out

    @classmethod
    def from_arrays(cls, arrays, source: str = "the model") -> "ViewModel":
        """Inverse of :meth:`to_arrays`, checked (the spreads: positive finite degrees).

        Parameters
        ----------
        arrays : mapping of str to array
            A model file's arrays.
        source : str
            The file's name in the messages.

        Raises
        ------
        WbsaError
            One line naming ``source`` and the member that is wrong.
        """
        from wbsa.errors import WbsaError

        spreads = {}
        for name, size in (("view_axis_sd_deg", 1), ("view_elevation_sd_deg", 2)):
            a = np.asarray(arrays.get(name, np.zeros(0)))
            if a.shape != (size,) or a.dtype.kind not in "iuf" or not np.all(np.isfinite(a)) or not np.all(a > 0):
                raise WbsaError(f"{source}: {name} must be {size} positive number(s) of degrees, got "
                                f"{a.tolist() if a.size <= 4 else a.shape}; the model file is damaged, rebuild it")
            spreads[name] = a.astype(float)
        el = spreads["view_elevation_sd_deg"]
        return cls(TreeEnsemble.from_arrays(arrays, "view_axis_", source),
                   TreeEnsemble.from_arrays(arrays, "view_front_", source),
                   float(spreads["view_axis_sd_deg"][0]), {"floor": float(el[0]), "axis": float(el[1])})
