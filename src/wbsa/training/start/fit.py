"""Train the learned start's network on its crops, and the figures it is judged by.

:func:`fit_start` standardises the targets (:func:`start_targets`) on the training bodies, then trains
:func:`~wbsa.estimation.methods.body_fit.start_net.build_net` with AdamW (cosine decay) on the Gaussian
negative log-likelihood of every output and the logistic loss of the sex, each crop seen as it is or mirrored
left to right (anny's bodies are symmetric: the mirrored view is the same body seen from the mirrored azimuth),
on one CPU thread: the same crops and settings give the same weights. :func:`start_figures` reads a
prediction against the truth: sex right (adults), mass, stature and age errors, azimuth error, and how
often the truth lies within the predicted spread. :func:`stature_sex_rule` is the baseline the sex is
compared with: one stature threshold learnt on the training crops.
"""

from __future__ import annotations

import numpy as np

from wbsa.estimation.methods.body_fit.start_net import GAUSSIAN_TARGETS, StartModel, build_net, scalar_inputs
from wbsa.errors import WbsaError
from wbsa.parallel import torch_threads
from wbsa.training.start.settings import StartSettings

#: Age (years) from which a subject counts as an adult in the sex figures.
ADULT_YEARS = 18.0


def start_targets(data: dict) -> np.ndarray:
    """(n, t) float64 truth of :data:`GAUSSIAN_TARGETS` for the crops of ``data``
    (:func:`wbsa.training.start.data.crop_chunk`'s arrays)."""
    az = np.radians(np.asarray(data["azimuth_deg"], dtype=np.float64))
    return np.column_stack([np.asarray(data["params"], dtype=np.float64), data["age_years"], np.log(data["mass_kg"]),
                            data["stature_m"], np.cos(az), np.sin(az)])


def validation_subjects(subject_ids: np.ndarray, settings: StartSettings) -> np.ndarray:
    """(n,) bool: crops of the bodies kept out of training (a seeded ``validation_fraction`` of the bodies)."""
    ids = np.asarray(subject_ids, dtype=np.int64)
    rng = np.random.default_rng(np.random.SeedSequence([settings.seed, 0x5A1D]))
    held = rng.random(int(ids.max()) + 1) < settings.validation_fraction
    return held[ids]


def _mirrored(images: np.ndarray, targets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Crops mirrored left to right and their targets (the azimuth's sine negated)."""
    t = targets.copy()
    t[:, GAUSSIAN_TARGETS.index("azimuth_sin")] *= -1.0
    return images[..., ::-1].copy(), t


def fit_start(data: dict, train: np.ndarray, settings: StartSettings, log=None) -> StartModel:
    """Train the network on the crops ``train`` selects.

    Parameters
    ----------
    data : dict of str to ndarray
        The crops and their truth (:func:`wbsa.training.start.data.start_crops`).
    train : (n,) bool
        The crops to train on (usable ones: ``data["ok"]``).
    settings : StartSettings
        Epochs, batch, learning rate, weight decay, seed.
    log : callable, optional
        ``log(line)`` after each epoch.

    Returns
    -------
    StartModel
        Its card holds the training's size (no timings: the same crops and settings give the same bytes).
    """
    import torch

    from wbsa.estimation.methods.body_fit.start_crop import CROP_SHAPE

    train = np.asarray(train, dtype=bool) & np.asarray(data["ok"], dtype=bool)
    if train.sum() < 2 * settings.batch:
        raise WbsaError(f"only {int(train.sum())} usable training crops for batches of {settings.batch}; use more "
                        "bodies or views")
    images = np.asarray(data["image"][train], dtype=np.float32)
    targets = start_targets({k: v[train] for k, v in data.items()})
    scalars = scalar_inputs(data["height_m"][train], data["floor_seen"][train]).astype(np.float64)
    male = np.asarray(data["male"][train], dtype=np.float32)
    t_mean, t_sd = targets.mean(0), targets.std(0)
    t_sd = np.where(t_sd > 1e-9, t_sd, 1.0)  # a target that does not vary (a local change left at 0)
    s_mean, s_sd = scalars.mean(0), scalars.std(0)
    s_sd = np.where(s_sd > 1e-9, s_sd, 1.0)
    z_t = ((targets - t_mean) / t_sd).astype(np.float32)
    z_s = ((scalars - s_mean) / s_sd).astype(np.float32)
    flipped, z_t_flipped = _mirrored(images, z_t.astype(np.float64))
    z_t_flipped = z_t_flipped.astype(np.float32)

    with torch_threads(1):
        net = build_net(CROP_SHAPE, settings.seed)
        opt = torch.optim.AdamW(net.parameters(), lr=settings.learning_rate, weight_decay=settings.weight_decay)
        n = len(images)
        steps = settings.epochs * (n // settings.batch)
        sched = torch.optim.lr_scheduler.LambdaLR(opt, lambda k: 0.5 * (1.0 + np.cos(np.pi * min(k, steps) / steps)))
        rng = np.random.default_rng(np.random.SeedSequence([settings.seed, 0x57A7]))
        net.train()
        for epoch in range(settings.epochs):
            order = rng.permutation(n)
            flip = rng.random(n) < 0.5
            total = 0.0
            for k in range(n // settings.batch):
                idx = order[k * settings.batch:(k + 1) * settings.batch]
                f = flip[idx]
                x = np.where(f[:, None, None, None], flipped[idx], images[idx])
                y = np.where(f[:, None], z_t_flipped[idx], z_t[idx])
                mean, log_var, logit = net(torch.as_tensor(x), torch.as_tensor(z_s[idx]))
                yt = torch.as_tensor(y)
                nll = 0.5 * (log_var + (yt - mean) ** 2 * torch.exp(-log_var)).mean()
                bce = torch.nn.functional.binary_cross_entropy_with_logits(logit, torch.as_tensor(male[idx]))
                loss = nll + bce
                opt.zero_grad()
                loss.backward()
                opt.step()
                sched.step()
                total += float(loss.detach())
            if log is not None:
                log(f"epoch {epoch + 1}/{settings.epochs}: loss {total / max(n // settings.batch, 1):.4f}")
    state = {k: v.detach().numpy().copy() for k, v in net.state_dict().items()}
    n_params = int(sum(p.numel() for p in net.parameters()))
    card = {"n_train_crops": int(n), "n_train_bodies": int(len(np.unique(data["subject_id"][train]))),
            "n_parameters": n_params}
    return StartModel(state, t_mean, t_sd, s_mean, s_sd, CROP_SHAPE, card)


def predict_crops(model: StartModel, data: dict, rows: np.ndarray, batch: int = 256) -> dict[str, np.ndarray]:
    """:meth:`StartModel.predict` over the crops ``rows`` selects (``(n,) bool``), in batches."""
    net = model.network()
    idx = np.flatnonzero(rows)
    parts = []
    for k in range(0, len(idx), batch):
        sel = idx[k:k + batch]
        parts.append(model.predict(data["image"][sel], scalar_inputs(data["height_m"][sel], data["floor_seen"][sel]),
                                   net))
    if not parts:
        return {}
    return {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}


def stature_sex_rule(height_m: np.ndarray, male: np.ndarray, age_years: np.ndarray) -> float:
    """The stature (m) above which an adult is read as a man, learnt on training crops: the threshold
    between two of the adults' crop heights that reads most of them right (the lowest such)."""
    adult = np.asarray(age_years) >= ADULT_YEARS
    h, m = np.asarray(height_m, dtype=np.float64)[adult], np.asarray(male, dtype=bool)[adult]
    if len(h) == 0:
        raise WbsaError("no adult among the training crops; the stature rule needs some")
    order = np.argsort(h, kind="stable")
    hs, ms = h[order], m[order]
    # threshold below crop i: crops i.. read male; right = women below + men at or above
    women_below = np.concatenate([[0], np.cumsum(~ms)])
    men_above = np.concatenate([np.cumsum(ms[::-1])[::-1], [0]])
    best = int(np.argmax(women_below + men_above))
    cuts = np.concatenate([[hs[0] - 1e-3], 0.5 * (hs[1:] + hs[:-1]), [hs[-1] + 1e-3]])
    return float(cuts[best])


def start_figures(pred: dict, truth: dict) -> dict[str, float]:
    """How a prediction reads the truth.

    Parameters
    ----------
    pred : dict
        :meth:`StartModel.predict`'s (or :func:`predict_crops`') arrays for n crops.
    truth : dict
        The crops' ``male``, ``age_years``, ``mass_kg``, ``stature_m``, ``azimuth_deg`` ((n,) arrays).

    Returns
    -------
    dict of str to float
        ``n``, ``n_adults``, ``sex_right_adults_pct``, ``mass_mape_pct``, ``mass_bias_pct``,
        ``stature_mae_cm``, ``age_mae_years``, ``age_mae_adults_years``, ``azimuth_median_deg``,
        ``azimuth_p90_deg``, and the share of the truth within one predicted spread (``within_1sd_mass_pct``,
        ``within_1sd_stature_pct``; 68 % when the spread is right).
    """
    mean, sd = pred["mean"], pred["sd"]
    col = {k: GAUSSIAN_TARGETS.index(k) for k in ("log_mass_kg", "stature_m", "age_years")}
    adult = np.asarray(truth["age_years"]) >= ADULT_YEARS
    mass = np.exp(mean[:, col["log_mass_kg"]])
    mass_err = 100.0 * (mass / np.asarray(truth["mass_kg"]) - 1.0)
    stature_err = mean[:, col["stature_m"]] - np.asarray(truth["stature_m"])
    age_err = np.abs(mean[:, col["age_years"]] - np.asarray(truth["age_years"]))
    az_err = np.abs((pred["azimuth_deg"] - np.asarray(truth["azimuth_deg"]) + 180.0) % 360.0 - 180.0)
    sex_right = (pred["p_male"] >= 0.5) == np.asarray(truth["male"], dtype=bool)
    z_mass = (mean[:, col["log_mass_kg"]] - np.log(truth["mass_kg"])) / sd[:, col["log_mass_kg"]]
    z_stature = stature_err / sd[:, col["stature_m"]]
    return {"n": int(len(mass)), "n_adults": int(adult.sum()),
            "sex_right_adults_pct": float(100.0 * sex_right[adult].mean()) if adult.any() else float("nan"),
            "mass_mape_pct": float(np.mean(np.abs(mass_err))), "mass_bias_pct": float(np.mean(mass_err)),
            "stature_mae_cm": float(100.0 * np.mean(np.abs(stature_err))),
            "age_mae_years": float(np.mean(age_err)),
            "age_mae_adults_years": float(np.mean(age_err[adult])) if adult.any() else float("nan"),
            "azimuth_median_deg": float(np.median(az_err)), "azimuth_p90_deg": float(np.percentile(az_err, 90)),
            "within_1sd_mass_pct": float(100.0 * np.mean(np.abs(z_mass) <= 1.0)),
            "within_1sd_stature_pct": float(100.0 * np.mean(np.abs(z_stature) <= 1.0))}
