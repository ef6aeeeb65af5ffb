"""The learned start's network: a small CNN from a :class:`~wbsa.estimation.methods.body_fit.start_crop.StartCrop`
to anny's parameters, the body's mass, stature and age, and the view's azimuth, each with a predictive spread.

Four 3 × 3 convolutions (:data:`CHANNELS`, each followed by a ReLU and a 2 × 2 max pool: 96 × 64 → 6 × 4)
read the crop; their features, with the crop's log height and whether a floor was seen, go through one
hidden layer (:data:`HIDDEN` units) to a mean and a log variance of every :data:`GAUSSIAN_TARGETS` output (in
units standardised on the training set) and one logit of the subject being male. The network is trained
with the Gaussian negative log-likelihood and the logistic loss (:mod:`wbsa.training.start.fit`); the azimuth
is read as the angle of its (cos, sin) pair. :class:`StartModel` holds the network with the standardisation
it was trained with and is written as numbers only (``.npz``: the weights, the standardisation, a card).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wbsa.bodies.body_model import BODY_PARAMETER_COLUMNS
from wbsa.errors import WbsaError

#: Outputs with a Gaussian spread, in order: anny's phenotypes and local changes, then the body's age, log mass
#: and stature, then the cosine and sine of the view's azimuth.
GAUSSIAN_TARGETS = (*BODY_PARAMETER_COLUMNS, "age_years", "log_mass_kg", "stature_m", "azimuth_cos", "azimuth_sin")
#: The scalar inputs beside the picture: the log of the crop's height (m) and whether a floor was seen (0 or 1).
SCALAR_INPUTS = ("log_height_m", "floor_seen")
#: Output channels of the four convolutions.
CHANNELS = (12, 24, 48, 64)
#: Units of the hidden layer.
HIDDEN = 96
#: Bounds of the predicted log variance (standardised units): a spread of 0.007 to 20 standard deviations.
LOG_VAR_LIMITS = (-10.0, 6.0)
#: Format tag of a written :class:`StartModel`.
FORMAT = "wbsa-start-model"
#: Version of the format; a file of another version is refused.
VERSION = 1


def build_net(crop_shape: tuple[int, int], seed: int):
    """The untrained network, its weights drawn from ``seed`` (torch's default initialisation).

    Parameters
    ----------
    crop_shape : (int, int)
        Rows and columns of the crop (each divisible by 16).
    seed : int

    Returns
    -------
    torch.nn.Module
        ``net(image (b, 2, rows, cols) float32, scalars (b, 2) float32)`` →
        ``(mean (b, t), log_var (b, t), sex_logit (b,))``, ``t = len(GAUSSIAN_TARGETS)``.
    """
    import torch
    from torch import nn

    rows, cols = crop_shape
    if rows % 16 or cols % 16:
        raise WbsaError(f"crop shape {crop_shape} must have rows and columns divisible by 16, e.g. (96, 64)")
    n_out = len(GAUSSIAN_TARGETS)

    class StartNet(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            layers, c_in = [], 2
            for c in CHANNELS:
                layers += [nn.Conv2d(c_in, c, 3, padding=1), nn.ReLU(), nn.MaxPool2d(2)]
                c_in = c
            self.features = nn.Sequential(*layers, nn.Flatten())
            n_feat = CHANNELS[-1] * (rows // 16) * (cols // 16)
            self.head = nn.Sequential(nn.Linear(n_feat + len(SCALAR_INPUTS), HIDDEN), nn.ReLU(),
                                      nn.Linear(HIDDEN, 2 * n_out + 1))

        def forward(self, image, scalars):
            out = self.head(torch.cat([self.features(image), scalars], dim=1))
            log_var = torch.clamp(out[:, n_out:2 * n_out], *LOG_VAR_LIMITS)
            return out[:, :n_out], log_var, out[:, -1]

    gen_state = torch.random.get_rng_state()
    torch.manual_seed(int(seed))
    try:
        net = StartNet()
    finally:
        torch.random.set_rng_state(gen_state)
    return net


def scalar_inputs(height_m: np.ndarray, floor_seen: np.ndarray) -> np.ndarray:
    """(b, 2) float32 :data:`SCALAR_INPUTS` of crops: their log height and whether a floor was seen.

    Parameters
    ----------
    height_m : (b,) float
        :attr:`StartCrop.height_m` of each crop.
    floor_seen : (b,) bool
    """
    return np.stack([np.log(np.asarray(height_m, dtype=np.float64)),
                     np.asarray(floor_seen, dtype=np.float64)], axis=1).astype(np.float32)


@dataclass
class StartModel:
    """A trained learned start: the network's weights and the standardisation of its targets.

    Attributes
    ----------
    state : dict of str to ndarray
        The network's weights (:func:`build_net`'s ``state_dict`` as arrays).
    target_mean, target_sd : (t,) float64
        The standardisation of :data:`GAUSSIAN_TARGETS` (training-set mean and standard deviation).
    scalar_mean, scalar_sd : (2,) float64
        The standardisation of :data:`SCALAR_INPUTS`.
    crop_shape : (int, int)
    card : dict
        The model card: data, settings, held-out figures.
    """

    state: dict
    target_mean: np.ndarray
    target_sd: np.ndarray
    scalar_mean: np.ndarray
    scalar_sd: np.ndarray
    crop_shape: tuple[int, int]
    card: dict = field(default_factory=dict)

    def network(self):
        """The network with these weights (eval mode)."""
        import torch

        net = build_net(self.crop_shape, 0)
        net.load_state_dict({k: torch.as_tensor(v) for k, v in self.state.items()})
        return net.eval()

    def predict(self, images: np.ndarray, scalars: np.ndarray, net=None) -> dict[str, np.ndarray]:
        """Each output's mean and spread for a batch of crops.

        Parameters
        ----------
        images : (b, 2, rows, cols) float32
            :attr:`StartCrop.image` of each crop.
        scalars : (b, 2) float32
            :func:`scalar_inputs` of the crops.
        net : torch.nn.Module, optional
            :meth:`network`, built once by a caller predicting many batches.

        Returns
        -------
        dict of str to ndarray
            ``mean`` and ``sd`` ((b, t) float64, in the targets' own units: :data:`GAUSSIAN_TARGETS`),
            ``p_male`` ((b,) float64), ``azimuth_deg`` ((b,) float64 in [0, 360)).
        """
        import torch

        net = self.network() if net is None else net
        z = (np.asarray(scalars, dtype=np.float64) - self.scalar_mean) / self.scalar_sd
        with torch.no_grad():
            mean, log_var, logit = net(torch.as_tensor(np.asarray(images, dtype=np.float32)),
                                       torch.as_tensor(z.astype(np.float32)))
        mean = mean.double().numpy() * self.target_sd + self.target_mean
        sd = np.exp(0.5 * log_var.double().numpy()) * self.target_sd
        c, s = (mean[:, GAUSSIAN_TARGETS.index(k)] for k in ("azimuth_cos", "azimuth_sin"))
        return {"mean": mean, "sd": sd, "p_male": 1.0 / (1.0 + np.exp(-logit.double().numpy())),
                "azimuth_deg": np.degrees(np.arctan2(s, c)) % 360.0}

    def save(self, path: str | os.PathLike) -> Path:
        """Write the model as one ``.npz`` of numbers, atomically (the same bytes for the same model).

        Parameters
        ----------
        path : path-like
            The ``.npz`` file to write.
        """
        from wbsa.io import write_npz

        arrays = {f"state/{k}": np.asarray(v) for k, v in self.state.items()}
        arrays.update(target_mean=self.target_mean, target_sd=self.target_sd, scalar_mean=self.scalar_mean,
                      scalar_sd=self.scalar_sd, crop_shape=np.asarray(self.crop_shape, dtype=np.int64))
        meta = {"format": FORMAT, "version": VERSION, "targets": list(GAUSSIAN_TARGETS), "card": self.card}
        arrays["meta_json"] = np.array(json.dumps(meta, sort_keys=True))
        return write_npz(arrays, path)

    @classmethod
    def load(cls, path: str | os.PathLike) -> "StartModel":
        """Read a model :meth:`save` wrote (numbers only; no code is loaded).

        Parameters
        ----------
        path : path-like
        """
        path = Path(path)
        try:
            with np.load(path, allow_pickle=False) as z:
                arrays = {k: z[k] for k in z.files}
        except (OSError, ValueError) as exc:
            raise WbsaError(f"{path} is not a readable start model ({type(exc).__name__}); give the start.npz that "
                            "wbsa train-start wrote") from None
        meta = json.loads(str(arrays.pop("meta_json", np.array("{}"))))
        if meta.get("format") != FORMAT or meta.get("version") != VERSION:
            raise WbsaError(f"{path} is not a version-{VERSION} start model; rebuild it with wbsa train-start")
        if tuple(meta.get("targets", ())) != GAUSSIAN_TARGETS:
            raise WbsaError(f"{path} predicts other outputs than this wbsa's start; rebuild it with wbsa train-start")
        state = {k.split("/", 1)[1]: v for k, v in arrays.items() if k.startswith("state/")}
        return cls(state, arrays["target_mean"], arrays["target_sd"], arrays["scalar_mean"], arrays["scalar_sd"],
                   tuple(int(v) for v in arrays["crop_shape"]), meta.get("card", {}))
