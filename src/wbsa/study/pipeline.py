"""The end-to-end study: population → scan (one per camera distance) → fit → report (``wbsa run``).

Layout of a study folder ``DIR``::

    DIR/study.toml                      the resolved settings (every key), to re-run the study
    DIR/study.json                      manifest: stage keys and folders, this run's timings, versions
    DIR/fits.parquet, DIR/fits.csv      the per-view fit table (copy of the fit stage's)
    DIR/model.json                      the fitted models (copy of the fit stage's)
    DIR/report.html                     the report (copy of the report stage's)
    DIR/stages/population-<key>/        population.parquet
    DIR/stages/scan-<key>/              one per camera distance: scan.parquet, parts/, settings.json
    DIR/stages/fit-<key>/               the outputs of wbsa fit (fits, residuals, QQ, formulae, model.json)
    DIR/stages/report-<key>/            report.html

Each stage folder is addressed by the hash of its settings and of its inputs' keys
(:mod:`wbsa.study.stages`); a finished one is reused, so re-running a study, or changing only a later
stage's settings, redoes only what changed.
"""

from __future__ import annotations

import dataclasses
import os
import platform
import shutil
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, TextIO

from wbsa import __version__
from wbsa.analysis.data import reference_distance
from wbsa.core.versions import package_versions
from wbsa.errors import WbsaError
from wbsa.io import atomic_path, write_json
from wbsa.study.settings import StudySettings, fit_settings, scan_settings
from wbsa.study.stages import Stage

#: Top-level files of a study folder.
MANIFEST_FILE = "study.json"
SETTINGS_FILE = "study.toml"
REPORT_FILE = "report.html"

#: The paper's camera distance; the listed distance nearest to it is the study's reference distance.


@dataclass
class StageRun:
    """What happened to one stage in this run.

    Attributes
    ----------
    name : str
        Stage label (``population``, ``scan 4.3 m``, ``fit``, ``report``).
    stage : Stage
    reused : bool
        Finished in an earlier run, skipped now.
    seconds : float
        Time spent in this run (≈ 0 when reused).
    original_seconds : float
        Time the stage took when it was computed.
    summary : str
        One-line description of the result.
    """

    name: str
    stage: Stage
    reused: bool
    seconds: float
    original_seconds: float
    summary: str = ""


@dataclass
class StudyResult:
    """The outcome of :func:`run_study`.

    Attributes
    ----------
    out_dir : Path
    report_path : Path
        ``DIR/report.html``.
    fits_path : Path
        ``DIR/fits.parquet``.
    stages : list of StageRun
    seconds : float
        Wall-clock time of this run.
    """

    out_dir: Path
    report_path: Path
    fits_path: Path
    stages: list[StageRun] = field(default_factory=list)
    seconds: float = 0.0


class _Log:
    """One line per stage on ``stream``: name, what it did, time."""

    def __init__(self, stream: TextIO | None) -> None:
        self.stream = stream

    def line(self, text: str) -> None:
        if self.stream is not None:
            self.stream.write(text + "\n")
            self.stream.flush()

    def stage(self, run: StageRun) -> None:
        if run.reused:
            self.line(f"{run.name:<12} reused {run.stage.path.name} ({run.summary}; took {run.original_seconds:.1f} s "
                      "when computed)")
        else:
            self.line(f"{run.name:<12} {run.summary} ({run.seconds:.1f} s) -> {run.stage.path.name}")


def run_study(settings: StudySettings, out_dir: str | os.PathLike, *, workers: int | None = None,
              show_progress: bool | None = None, stream: TextIO | None | str = "stderr",
              scan_chunk_fn: Callable | None = None) -> StudyResult:
    """Run (or resume) a whole study into ``out_dir``.

    Parameters
    ----------
    settings : StudySettings
        From :func:`wbsa.study.settings.load_settings`.
    out_dir : path
        The study folder; finished stages found there are reused.
    workers : int, optional
        Scan and population worker processes; overrides ``[run] workers`` (0 = all cores).
    show_progress : bool, optional
        Progress bars of the long stages (default: when stderr is a terminal).
    stream : text stream, None or ``'stderr'``
        Where the per-stage lines go (default: the current ``sys.stderr``; None: silent).
    scan_chunk_fn : callable, optional
        Replacement scan worker, for tests of the engine wiring only.

    Returns
    -------
    StudyResult
    """
    t0 = time.perf_counter()
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise WbsaError(f"--out {out} is a file; give a folder for the study")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise WbsaError(f"cannot create study folder {out}: {exc.strerror}; choose a writable --out") from None
    log = _Log(sys.stderr if stream == "stderr" else stream)
    n_workers = settings.run.workers if workers is None else int(workers)
    if n_workers < 0:
        raise WbsaError(f"--workers must be 0 (all cores) or more, got {n_workers}")
    if n_workers == 0:
        from wbsa.parallel import default_workers

        n_workers = default_workers()
    scheduler = settings.run.scheduler or None
    with atomic_path(out / SETTINGS_FILE) as tmp:
        tmp.write_text(settings.to_toml())
    log.line(f"study {settings.study.name!r} -> {out} (settings: {settings.source})")

    runs: list[StageRun] = []
    pop = _population_stage(settings, out, n_workers, scheduler, show_progress)
    runs.append(pop)
    log.stage(pop)
    scans = []
    for d in settings.scan.distances_m:
        run = _scan_stage(settings, out, d, pop.stage, n_workers, scheduler, show_progress, scan_chunk_fn)
        runs.append(run)
        scans.append(run)
        log.stage(run)
    fit = _fit_stage(settings, out, pop.stage, [s.stage for s in scans], show_progress)
    runs.append(fit)
    log.stage(fit)

    manifest = _manifest(settings, out, runs, time.perf_counter() - t0)
    write_json(manifest, out / MANIFEST_FILE)
    rep = _report_stage(settings, out, pop.stage, [s.stage for s in scans], fit.stage, show_progress)
    runs.append(rep)
    log.stage(rep)

    fits_path = _publish(out, fit.stage, rep.stage)
    seconds = time.perf_counter() - t0
    write_json(_manifest(settings, out, runs, seconds), out / MANIFEST_FILE)
    log.line(f"study finished in {seconds:.1f} s ({sum(r.reused for r in runs)} of {len(runs)} stages reused)")
    return StudyResult(out_dir=out, report_path=out / REPORT_FILE, fits_path=fits_path, stages=runs, seconds=seconds)


def _reused(name: str, stage: Stage) -> StageRun:
    rec = stage.record()
    return StageRun(name, stage, True, 0.0, float(rec.get("seconds", 0.0)), rec.get("info", {}).get("summary", ""))


def _population_stage(settings: StudySettings, out: Path, workers: int, scheduler: str | None,
                      show_progress: bool | None) -> StageRun:
    cfg = settings.population
    stage = Stage.create(out, "population", dataclasses.asdict(cfg))
    if stage.done:
        return _reused("population", stage)
    from wbsa.io import write_table
    from wbsa.bodies.build import build_population

    t = time.perf_counter()
    df = build_population(cfg.kind, n=cfg.n, seed=cfg.seed, density_kg_m3=cfg.density_kg_m3,
                          density_model=cfg.density_model, sampling=cfg.sampling,
                          variations=cfg.variations, show_progress=show_progress, workers=workers,
                          scheduler=scheduler)
    write_table(df, stage.path / "population.parquet")
    seconds = time.perf_counter() - t
    summary = f"{len(df)} {cfg.kind} subjects"
    stage.finish(seconds, {"population": "population.parquet"},
                 {"summary": summary, "n_subjects": len(df), "subjects_per_s": len(df) / seconds if seconds else None,
                  "workers": workers})
    return StageRun("population", stage, False, seconds, seconds, summary)


def _scan_stage(settings: StudySettings, out: Path, distance_m: float, pop: Stage, workers: int,
                scheduler: str | None, show_progress: bool | None, chunk_fn: Callable | None) -> StageRun:
    ss = scan_settings(settings, distance_m)
    name = f"scan {distance_m:g} m"
    stage = Stage.create(out, "scan", ss.to_dict(), {"population": pop.key})
    if stage.done:
        return _reused(name, stage)
    from wbsa.scan.engine import scan_population

    t = time.perf_counter()
    result = scan_population(pop.path / "population.parquet", ss, stage.path, workers=workers, scheduler=scheduler,
                             chunk_fn=chunk_fn, show_progress=show_progress)
    seconds = time.perf_counter() - t
    n_subjects = int(result.table["subject_id"].nunique())
    rate = result.n_views_scanned / result.seconds if result.seconds > 0 else float("nan")
    in_frame = float(result.table["fits_in_frame"].mean()) if "fits_in_frame" in result.table else float("nan")
    summary = (f"{n_subjects} subjects x {len(ss.views)} views = {len(result.table)} rows ({rate:.1f} views/s, "
               f"{100 * in_frame:.0f}% in frame)")
    stage.finish(seconds, {"scan": "scan.parquet"},
                 {"summary": summary, "distance_m": distance_m, "n_rows": len(result.table), "n_subjects": n_subjects,
                  "n_views": len(ss.views), "n_views_scanned": result.n_views_scanned, "views_per_s": rate,
                  "n_chunks": result.n_chunks, "n_resumed": result.n_resumed, "workers": workers,
                  "fraction_in_frame": in_frame})
    return StageRun(name, stage, False, seconds, seconds, summary)


def _fit_stage(settings: StudySettings, out: Path, pop: Stage, scans: list[Stage],
               show_progress: bool | None) -> StageRun:
    fs = fit_settings(settings)
    ref = reference_distance(settings.scan.distances_m)
    corr = tuple(float(a) for a in settings.fit.correlation_view_deg)
    stage = Stage.create(out, "fit", {"fit": fs.to_dict(), "correlation_view_deg": list(corr),
                                      "correlation_distance_m": ref},
                         {"population": pop.key, "scans": [s.key for s in scans]})
    if stage.done:
        return _reused("fit", stage)
    import pandas as pd

    from wbsa.analysis.outputs import run_fit
    from wbsa.io import write_table

    t = time.perf_counter()
    scan_paths = [s.path / "scan.parquet" for s in scans]
    outputs = {}
    if len(scan_paths) == 1:
        scan_path = scan_paths[0]
    else:  # one table of every distance: the fit treats each distance's views as views of their own
        scan_path = write_table(pd.concat([pd.read_parquet(p) for p in scan_paths], ignore_index=True),
                                stage.path / "scans.parquet")
        outputs["scans"] = "scans.parquet"
    result, paths = run_fit(pop.path / "population.parquet", scan_path, stage.path, fs, corr,
                            show_progress=show_progress, nearest_correlation_view=True)
    seconds = time.perf_counter() - t
    info = result.info
    summary = (f"{info['n_fits']} fits: {info['n_subjects']} subjects x {info['n_views']} views, "
               f"{len(fs.groups)} groups x {len(fs.models)} models x {len(fs.predictor_sets)} predictor sets, "
               f"k = {fs.k}" + (f", {info['n_skipped']} skipped" if info["n_skipped"] else ""))
    outputs.update({k: p.name for k, p in paths.items()})
    stage.finish(seconds, outputs, {"summary": summary, **{k: v for k, v in info.items() if k != "seconds"},
                                    "reference_distance_m": ref})
    return StageRun("fit", stage, False, seconds, seconds, summary)


def _report_stage(settings: StudySettings, out: Path, pop: Stage, scans: list[Stage], fit: Stage,
                  show_progress: bool | None) -> StageRun:
    rcfg = dataclasses.asdict(settings.report)
    stage = Stage.create(out, "report", {"report": rcfg, "study": dataclasses.asdict(settings.study)},
                         {"population": pop.key, "scans": [s.key for s in scans], "fit": fit.key})
    if stage.done:
        return _reused("report", stage)
    from wbsa.report.build import build_report
    from wbsa.report.sources import study_sources

    t = time.perf_counter()
    result = build_report(study_sources(out), stage.path / REPORT_FILE, settings.report)
    seconds = time.perf_counter() - t
    summary = f"{len(result.figures)} figures, {len(result.tables)} tables"
    stage.finish(seconds, {"report": REPORT_FILE}, {"summary": summary, "figures": result.figures,
                                                    "tables": result.tables})
    return StageRun("report", stage, False, seconds, seconds, summary)


def _publish(out: Path, fit: Stage, report: Stage) -> Path:
    """Copy the fit table (Parquet, CSV), the model file and the report to the top of the study folder."""
    for src, dst in ((fit.path / "fits.parquet", out / "fits.parquet"), (fit.path / "fits.csv", out / "fits.csv"),
                     (fit.path / "model.json", out / "model.json"), (report.path / REPORT_FILE, out / REPORT_FILE)):
        if src.is_file():
            with atomic_path(dst) as tmp:
                shutil.copyfile(src, tmp)
    return out / "fits.parquet"


def _manifest(settings: StudySettings, out: Path, runs: list[StageRun], seconds: float) -> dict:
    stages = []
    for r in runs:
        stages.append({"name": r.name, "stage": r.stage.name, "key": r.stage.key,
                       "path": str(r.stage.path.relative_to(out)), "reused": r.reused,
                       "seconds_this_run": r.seconds, "seconds_computed": r.original_seconds, "summary": r.summary,
                       "inputs": r.stage.inputs})
    return {
        "study": dataclasses.asdict(settings.study),
        "source": settings.source,
        "settings": settings.to_dict(),
        "reference_distance_m": reference_distance(settings.scan.distances_m),
        "stages": stages,
        "seconds": seconds,
        "finished": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "versions": package_versions(),
        "platform": {"system": platform.platform(), "processor": platform.machine(), "cpus": os.cpu_count()},
    }
