"""Judge the body fit's learned start (``wbsa train-start``) on the held-out room captures of bench_estimate.py.

The same subjects (random, ages 3–80, and survey-matched NHANES people), postures, rooms, cameras, distances,
views and sensor effects as ``benchmarks/bench_estimate.py`` and ``bench_body_fit.py`` with the same ``--seed``
and ``--subjects`` (:func:`wbsa.testing.testset.room_test_captures`); each capture is segmented as a real frame is
(:func:`~wbsa.estimation.subject.segment.segment_subject`), cropped
(:func:`~wbsa.estimation.methods.body_fit.start_crop.start_crop`) and read by the start model. Printed, over the
captures and beside the baselines: sex right (adults, 18 years and over), mass MAPE and bias, stature and age
errors, azimuth error, the share of the truth within one predicted spread; the baselines are the stature-only
sex rule learnt on the start's own training crops (its threshold is in the model's card) and, with ``--grid``,
the sex of the grid start's best guess (:func:`wbsa.estimation.methods.body_fit.init.first_guesses`, what the
fit starts from today). Survey people that the start's training drew are dropped from the figures (counted).

    python benchmarks/bench_start.py --model RUN/start.npz --subjects 60 --seed 1000 --grid [--out rows.csv]
    python benchmarks/bench_start.py --model RUN/start.npz --subjects 60 --grid --captures held-out.npz  # kept
"""

from __future__ import annotations

import argparse
import io
import json
import sys
import time

import numpy as np
import pandas as pd


def judge_chunk(population: pd.DataFrame, others: pd.DataFrame, first: int, seed: int,
                grid: bool) -> tuple[pd.DataFrame, np.ndarray]:
    """Capture, segment and crop every subject of ``population``; with ``grid`` also read the grid start's sex.

    Returns the rows (truth, capture, crop's height, the grid's gender) and the (n, 2, rows, cols) crops (zeros
    where the capture failed: ``error``)."""
    import torch

    from wbsa.bodies.body_model import BodyModel
    from wbsa.errors import WbsaError
    from wbsa.estimation.methods.body_fit.start_crop import CROP_SHAPE, start_crop
    from wbsa.estimation.subject.segment import SegmentSettings, segment_subject
    from wbsa.parallel import single_threaded_math
    from wbsa.sensor.technology import envelope_model
    from wbsa.testing.testset import RoomTestSettings, room_test_captures

    torch.set_num_threads(1)
    settings = RoomTestSettings(seed=seed)
    rows, images = [], []
    with single_threaded_math():
        body_model = BodyModel()
        for tc in room_test_captures(population, others, first, settings, body_model):
            t = population.iloc[tc.index - first]
            cam = tc.capture.camera
            row = {k: t[k] for k in ("subject_id", "population", "survey_id", "sex", "age_years", "stature_m",
                                     "mass_kg") if k in t.index}
            row.update(image=tc.index, posture=tc.posture, camera=cam.name, azimuth_deg=tc.capture.view.azimuth_deg,
                       distance_m=tc.capture.view.distance_m, second_person=tc.second_person, error="")
            try:
                sensor = envelope_model(cam)
                seg = segment_subject(tc.depth_m, cam, SegmentSettings(pick=settings.pick), sensor=sensor)
                t0 = time.perf_counter()
                crop = start_crop(tc.depth_m, seg.mask, cam, seg.floor)
                row.update(crop_seconds=time.perf_counter() - t0, crop_height_m=crop.height_m,
                           floor_seen=crop.floor_seen)
                image = crop.image
                if grid:
                    t0 = time.perf_counter()
                    row.update(grid_p_gender=_grid_gender(tc.depth_m, seg.mask, cam, seg.floor, sensor, tc.index),
                               grid_seconds=time.perf_counter() - t0)
            except WbsaError as exc:
                row.update(error=str(exc))
                image = np.zeros((2, *CROP_SHAPE), np.float32)
            rows.append(row)
            images.append(image)
    return pd.DataFrame(rows), np.stack(images)


def read_crops(table: pd.DataFrame, images: np.ndarray, model_path: str) -> pd.DataFrame:
    """``table`` with the start model's reading of each crop (``p_male``, ``est_azimuth_deg``, ``est_<output>``
    and ``sd_<output>`` of every :data:`GAUSSIAN_TARGETS` output); NaN where the capture failed."""
    from wbsa.estimation.methods.body_fit.start_net import GAUSSIAN_TARGETS, StartModel, scalar_inputs

    out = table.copy()
    ok = (out["error"] == "").to_numpy()
    model = StartModel.load(model_path)
    pred = model.predict(images[ok], scalar_inputs(out.loc[ok, "crop_height_m"], out.loc[ok, "floor_seen"]))
    out.loc[ok, "p_male"] = pred["p_male"]
    out.loc[ok, "est_azimuth_deg"] = pred["azimuth_deg"]
    for j, name in enumerate(GAUSSIAN_TARGETS):
        out.loc[ok, f"est_{name}"] = pred["mean"][:, j]
        out.loc[ok, f"sd_{name}"] = pred["sd"][:, j]
    return out


def _grid_gender(depth, mask, camera, floor, sensor, index: int) -> float:
    """anny's gender parameter (0 male, 1 female) of the grid start's best guess, as the fit builds it."""
    import torch

    from wbsa.bodies.body_model import PHENOTYPE_COLUMNS
    from wbsa.estimation.methods.body_fit.fit import _models
    from wbsa.estimation.methods.body_fit.init import first_guesses
    from wbsa.estimation.methods.body_fit.objective import Objective
    from wbsa.estimation.methods.body_fit.observation import check_inputs, observe
    from wbsa.estimation.methods.body_fit.settings import BodyFitSettings

    s = BodyFitSettings()
    _, fit_model, _ = _models(s.vertex_spacing_m)
    depth, mask = check_inputs(depth, mask, camera)
    rng = np.random.default_rng(np.random.SeedSequence([int(index), 0xB0D7]))
    obs = observe(depth, mask, camera, floor, s.n_points, rng, sensor)
    objective = Objective(obs, s.robust_loss, s.robust_scale_m, s.silhouette_tolerance_px, obs.sensor)
    with torch.no_grad():
        starts = first_guesses(fit_model, objective, 1, None, s.child_starts)
    return float(starts.params[0, PHENOTYPE_COLUMNS.index("p_gender")])


def training_survey_ids(card: dict) -> set:
    """The NHANES people the start's training drew (its settings' survey count and seed + 1)."""
    from wbsa.bodies.survey_data import load_survey, select_people

    s = card.get("settings", {})
    n, seed = int(s.get("n_survey", 0)), int(s.get("seed", 0))
    if n <= 0:
        return set()
    return set(select_people(load_survey(None).people, n, seed + 1)["survey_id"])


def summarise(table: pd.DataFrame, threshold_m: float) -> pd.DataFrame:
    """One row per reader (the start, the stature rule, the grid start) of the figures over ``table``."""
    from wbsa.estimation.methods.body_fit.start_net import GAUSSIAN_TARGETS
    from wbsa.training.start.fit import ADULT_YEARS, start_figures

    ok = table[table["error"] == ""].reset_index(drop=True)
    adult = ok["age_years"].to_numpy() >= ADULT_YEARS
    male = (ok["sex"] == "male").to_numpy()
    pred = {"mean": ok[[f"est_{k}" for k in GAUSSIAN_TARGETS]].to_numpy(),
            "sd": ok[[f"sd_{k}" for k in GAUSSIAN_TARGETS]].to_numpy(),
            "p_male": ok["p_male"].to_numpy(), "azimuth_deg": ok["est_azimuth_deg"].to_numpy()}
    truth = {"male": male, "age_years": ok["age_years"].to_numpy(), "mass_kg": ok["mass_kg"].to_numpy(),
             "stature_m": ok["stature_m"].to_numpy(), "azimuth_deg": ok["azimuth_deg"].to_numpy()}
    out = [{"reader": "learned start", **start_figures(pred, truth)}]
    rule = ok["crop_height_m"].to_numpy() > threshold_m
    out.append({"reader": f"stature rule (> {threshold_m:.3f} m)", "n": len(ok), "n_adults": int(adult.sum()),
                "sex_right_adults_pct": float(100 * np.mean(rule[adult] == male[adult]))})
    if "grid_p_gender" in ok:
        g = ok["grid_p_gender"].to_numpy() < 0.5
        out.append({"reader": "grid start (best guess)", "n": len(ok), "n_adults": int(adult.sum()),
                    "sex_right_adults_pct": float(100 * np.mean(g[adult] == male[adult]))})
    return pd.DataFrame(out)


def vars_of(args: argparse.Namespace) -> dict:
    """The options the captures depend on."""
    return {"subjects": args.subjects, "survey_share": args.survey_share, "seed": args.seed, "grid": args.grid}


def record_table(path) -> str:
    """The rows kept with the crops in a ``--captures`` file (JSON)."""
    with np.load(path, allow_pickle=False) as z:
        return str(z["table"])


def main(argv=None) -> int:
    """Run the benchmark (see the module doc)."""
    from pathlib import Path

    from wbsa.estimation.methods.body_fit.start_net import StartModel
    from wbsa.parallel import map_chunks
    from wbsa.testing.testset import held_out_population

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default=None, help="the start.npz wbsa train-start wrote (without it: only capture "
                                                  "into --captures)")
    ap.add_argument("--subjects", type=int, default=60)
    ap.add_argument("--survey-share", type=float, default=0.4)
    ap.add_argument("--seed", type=int, default=1000, help="the held-out benchmark's seed (default 1000)")
    ap.add_argument("--grid", action="store_true", help="also the grid start's sex (a few seconds per image)")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--chunk", type=int, default=10)
    ap.add_argument("--out", default=None, help="CSV of one row per capture")
    ap.add_argument("--captures", default=None, metavar="FILE.npz",
                    help="keep the segmented crops there, and read them from there on a later run with the same "
                         "options (another model judged on the same captures without capturing them again)")
    args = ap.parse_args(argv)
    if args.model is None and args.captures is None:
        sys.exit("error: give --model RUN/start.npz, or --captures FILE.npz to capture only")
    if args.model is not None and not Path(args.model).is_file():
        sys.exit(f"error: --model {args.model} is not a file; give the start.npz wbsa train-start wrote")
    t0 = time.perf_counter()
    cache = Path(args.captures) if args.captures else None
    if cache is not None and cache.is_file():  # the captures of an earlier run with the same options
        with np.load(cache, allow_pickle=False) as z:
            images, record = z["images"], json.loads(str(z["record"]))
        if record != vars_of(args):
            sys.exit(f"error: {cache} holds captures of other options ({record}); give another --captures file")
        table = pd.read_json(io.StringIO(record_table(cache)))
    else:
        pop = held_out_population(args.subjects, args.survey_share, args.seed)
        others = pop.iloc[np.roll(np.arange(len(pop)), 1)].reset_index(drop=True)
        chunks = [(pop.iloc[s:s + args.chunk].reset_index(drop=True),
                   others.iloc[s:s + args.chunk].reset_index(drop=True), s, args.seed, args.grid)
                  for s in range(0, len(pop), args.chunk)]
        parts = map_chunks(judge_chunk, chunks, workers=args.workers, tag="bench-start")
        table = pd.concat([p[0] for p in parts], ignore_index=True)
        images = np.concatenate([p[1] for p in parts])
        if cache is not None:
            with open(cache, "wb") as fh:
                np.savez_compressed(fh, images=images, record=np.array(json.dumps(vars_of(args))),
                                    table=np.array(table.to_json()))
    if args.model is None:
        print(f"captured {len(table)} held-out subjects into {cache} ({time.perf_counter() - t0:.0f} s)")
        return 0
    card = StartModel.load(args.model).card
    table = read_crops(table, images, args.model)
    seen = training_survey_ids(card)
    overlap = table["survey_id"].isin(seen).to_numpy() if "survey_id" in table else np.zeros(len(table), bool)
    if args.out:
        table.to_csv(args.out, index=False)
    kept = table[~overlap]
    threshold = float(card["stature_sex_rule"]["threshold_m"])
    print(f"held-out captures: seed {args.seed}, {len(table)} subjects ({int(overlap.sum())} survey people the "
          f"start trained on dropped; {int((kept['error'] != '').sum())} failed to segment or crop), "
          f"{time.perf_counter() - t0:.0f} s")
    print(f"start model: {card.get('data', {})}")
    with pd.option_context("display.width", 200, "display.max_columns", 30, "display.float_format", "{:.2f}".format):
        print(summarise(kept, threshold).to_string(index=False))
        ok = kept[kept["error"] == ""]
        by = ok.assign(adult=ok["age_years"] >= 18, right=(ok["p_male"] >= 0.5) == (ok["sex"] == "male"),
                       mass_err_pct=100 * np.abs(np.exp(ok["est_log_mass_kg"]) / ok["mass_kg"] - 1))
        print(by.groupby("population")[["right", "mass_err_pct"]].mean().to_string())
    return 0


if __name__ == "__main__":
    sys.exit(main())
