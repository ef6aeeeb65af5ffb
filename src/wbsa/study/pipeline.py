"""The end-to-end study: population → scan (one per camera distance) → fit → report (``wbsa run``).

Layout of a study folder ``DIR``::

    DIR/study.toml                      the resolved settings (every key), to re-run the study
    DIR/camera.json                     a copy of the camera intrinsics file, when [scan] camera names one
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
stage's settings, redoes only what changed. Every stage is self-describing: it is built from its own
settings and the folders of its input stages, never from the top-level files, which belong to the last
run that finished. Those top-level files are replaced as a group when a run finishes, ``study.json``
last (:func:`wbsa.atomic.staged_files`), so a run that fails leaves the previous ones as they were.

One run at a time writes a study folder: :func:`run_study` holds the folder's lock
(:mod:`wbsa.folder_lock`) and a second run on the same folder stops with a one-line error.
"""

from __future__ import annotations

import dataclasses
import os
import platform
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, TextIO

from wbsa.core.versions import WBSA_VERSION as __version__
from wbsa.analysis.data import reference_distance
from wbsa.core.versions import package_versions
from wbsa.errors import WbsaError
from wbsa.folder_lock import folder_lock
from wbsa.io import (RUN_LOG_ATTR, copy_file, remove_stale_temporaries, staged_files, write_json,
                     write_text)
from wbsa.parallel import RunSettings
from wbsa.settings_io import to_table
from wbsa.study.settings import StudySettings, fit_settings, scan_job
from wbsa.study.stages import Stage

#: Top-level files of a study folder.
MANIFEST_FILE = "study.json"
SETTINGS_FILE = "study.toml"
REPORT_FILE = "report.html"
#: Copy of a camera intrinsics file named by ``[scan] camera``, so ``study.toml`` can be re-run.
CAMERA_FILE = "camera.json"

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

    def __repr__(self) -> str:
        how = "reused" if self.reused else f"{self.seconds:.1f} s"
        return f"StageRun({self.name}: {self.summary or 'done'}; {how}; {self.stage.path.name})"


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

    def __repr__(self) -> str:
        reused = sum(r.reused for r in self.stages)
        return (f"StudyResult({self.out_dir}: report {self.report_path.name}, {len(self.stages)} stages "
                f"({reused} reused), {self.seconds:.1f} s)")

    def __str__(self) -> str:
        """A small table: one line per stage (name, what it did, time), then the report's path."""
        lines = [repr(self)]
        for r in self.stages:
            lines.append(f"  {r.name:<12} {'reused' if r.reused else f'{r.seconds:.1f} s':>9}  {r.summary}")
        lines.append(f"  report: {self.report_path}")
        return "\n".join(lines)


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
        Progress bars of the long stages; overrides ``[run] progress`` (None there: when stderr is a terminal).
    stream : text stream, None or ``'stderr'``
        Where the per-stage lines go (default: the current ``sys.stderr``; None: silent).
    scan_chunk_fn : callable, optional
        Replacement scan worker, for tests of the engine wiring only.

    Returns
    -------
    StudyResult

    Raises
    ------
    WbsaError
        Bad settings, another run writing the same folder, a stage that fails, a full disk.
    """
    t0 = time.perf_counter()
    out = Path(out_dir)
    log = _Log(sys.stderr if stream == "stderr" else stream)
    run = settings.run
    if workers is not None:
        run = dataclasses.replace(run, workers=int(workers))
    if show_progress is not None:
        run = dataclasses.replace(run, progress=show_progress)
    if run.scheduler is None:  # the worker count used, recorded in study.toml and the report (0 = all cores)
        run = dataclasses.replace(run, workers=run.n_workers)
    settings = dataclasses.replace(settings, run=run)
    with folder_lock(out, "study folder"):  # creates the folder, or names why it cannot
        remove_stale_temporaries(out, all_of_them=True)
        return _run_locked(settings, out, run, log, scan_chunk_fn, t0)


def _run_locked(settings: StudySettings, out: Path, run: RunSettings, log: _Log, scan_chunk_fn: Callable | None,
                t0: float) -> StudyResult:
    log.line(f"study {settings.study.name!r} -> {out} (settings: {settings.source})")
    runs: list[StageRun] = []
    pop = _population_stage(settings, out, run)
    runs.append(pop)
    log.stage(pop)
    scans = []
    for d in settings.scan.distances_m:
        scan = _scan_stage(settings, out, d, pop.stage, run, scan_chunk_fn)
        runs.append(scan)
        scans.append(scan)
        log.stage(scan)
    fit = _fit_stage(settings, out, pop.stage, [s.stage for s in scans], run.progress)
    runs.append(fit)
    log.stage(fit)

    rep = _report_stage(settings, out, runs, pop.stage, [s.stage for s in scans], fit.stage, run.progress,
                        time.perf_counter() - t0)
    runs.append(rep)
    log.stage(rep)

    seconds = time.perf_counter() - t0
    fits_path = _publish(settings, out, fit.stage, rep.stage, _manifest(settings, out, runs, seconds))
    log.line(f"study finished in {seconds:.1f} s ({sum(r.reused for r in runs)} of {len(runs)} stages reused)")
    return StudyResult(out_dir=out, report_path=out / REPORT_FILE, fits_path=fits_path, stages=runs, seconds=seconds)


def _reused(name: str, stage: Stage) -> StageRun:
    rec = stage.record()
    info = rec.get("info") if isinstance(rec.get("info"), dict) else {}
    seconds = rec.get("seconds")
    return StageRun(name, stage, True, 0.0, float(seconds) if isinstance(seconds, (int, float)) else 0.0,
                    str(info.get("summary", "")))


def _population_stage(settings: StudySettings, out: Path, run: RunSettings) -> StageRun:
    cfg = settings.population
    stage = Stage.create(out, "population", to_table(cfg))
    if stage.done:
        return _reused("population", stage)
    from wbsa.io import write_table
    from wbsa.bodies.build import build_population

    t = time.perf_counter()
    workers = run.n_workers
    df = build_population(**dataclasses.asdict(cfg), show_progress=run.progress, workers=workers,
                          scheduler=run.scheduler)
    write_table(df, stage.path / "population.parquet")
    seconds = time.perf_counter() - t
    summary = f"{len(df)} {cfg.kind} subjects"
    stage.finish(seconds, {"population": "population.parquet"},
                 {"summary": summary, "n_subjects": len(df), "subjects_per_s": len(df) / seconds if seconds else None,
                  "workers": workers, **({"run_log": df.attrs[RUN_LOG_ATTR]} if RUN_LOG_ATTR in df.attrs else {})})
    return StageRun("population", stage, False, seconds, seconds, summary)


def _scan_stage(settings: StudySettings, out: Path, distance_m: float, pop: Stage, run: RunSettings,
                chunk_fn: Callable | None) -> StageRun:
    ss = scan_job(settings, distance_m)
    name = f"scan {distance_m:g} m"
    stage = Stage.create(out, "scan", ss.to_dict(), {"population": pop.key})  # the job only: no execution knob
    if stage.done:
        return _reused(name, stage)
    from wbsa.scan.engine import scan_population

    t = time.perf_counter()
    workers = run.n_workers
    result = scan_population(pop.path / "population.parquet", ss, stage.path, workers=workers,
                             scheduler=run.scheduler, chunk_size=run.chunk_size, chunk_fn=chunk_fn,
                             show_progress=run.progress)
    seconds = time.perf_counter() - t
    if result.n_views_invalid == len(result.table):
        raise WbsaError(f"at {distance_m:g} m every view puts the camera inside the body (nothing to fit); "
                        "use larger [scan] distances_m")
    n_subjects = int(result.table["subject_id"].nunique())
    rate = result.n_views_scanned / result.seconds if result.seconds > 0 else float("nan")
    in_frame = float(result.table["fits_in_frame"].mean()) if "fits_in_frame" in result.table else float("nan")
    summary = (f"{n_subjects} subjects x {len(ss.views)} views = {len(result.table)} rows ({rate:.1f} views/s, "
               f"{100 * in_frame:.0f}% in frame"
               + (f", {result.n_views_invalid} with the camera inside the body, left out" if result.n_views_invalid
                  else "") + ")")
    stage.finish(seconds, {"scan": "scan.parquet"},
                 {"summary": summary, "distance_m": distance_m, "n_rows": len(result.table), "n_subjects": n_subjects,
                  "n_views": len(ss.views), "n_views_scanned": result.n_views_scanned, "views_per_s": rate,
                  "n_chunks": result.n_chunks, "n_resumed": result.n_resumed, "workers": workers,
                  "n_views_invalid": result.n_views_invalid,
                  "fraction_in_frame": in_frame})
    return StageRun(name, stage, False, seconds, seconds, summary)


def _fit_stage(settings: StudySettings, out: Path, pop: Stage, scans: list[Stage],
               show_progress: bool | None) -> StageRun:
    fs = fit_settings(settings)
    ref = reference_distance(settings.scan.distances_m)
    corr = tuple(float(a) for a in fs.correlation_view_deg)
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
    result, paths = run_fit(pop.path / "population.parquet", scan_path, stage.path, fs,
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


def _report_stage(settings: StudySettings, out: Path, runs: list[StageRun], pop: Stage, scans: list[Stage],
                  fit: Stage, show_progress: bool | None, seconds_so_far: float) -> StageRun:
    """The report of this run's own stages and settings (never read back from the shared ``study.json``)."""
    stage = Stage.create(out, "report", {"report": to_table(settings.report), "study": to_table(settings.study)},
                         {"population": pop.key, "scans": [s.key for s in scans], "fit": fit.key})
    if stage.done:
        return _reused("report", stage)
    from wbsa.report.build import build_report
    from wbsa.report.sources import ReportSources

    t = time.perf_counter()
    sources = ReportSources(fit_dir=fit.path, population_path=pop.path / "population.parquet",
                            scan_paths=tuple(s.path / "scan.parquet" for s in scans), study_dir=out,
                            manifest=_manifest(settings, out, runs, seconds_so_far),
                            stage_records=[{**r.stage.record(), "label": r.name} for r in runs])
    result = build_report(sources, stage.path / REPORT_FILE, settings.report)
    seconds = time.perf_counter() - t
    summary = f"{len(result.figures)} figures, {len(result.tables)} tables"
    stage.finish(seconds, {"report": REPORT_FILE}, {"summary": summary, "figures": result.figures,
                                                    "tables": result.tables})
    return StageRun("report", stage, False, seconds, seconds, summary)


def _publish(settings: StudySettings, out: Path, fit: Stage, report: Stage, manifest: dict) -> Path:
    """Replace the top-level files as one group: fit table (Parquet, CSV), model, report, settings, manifest last.

    ``study.toml`` names a camera intrinsics file by the copy ``camera.json`` beside it, so
    ``wbsa run --config DIR/study.toml`` re-runs the study from anywhere.
    """
    with staged_files(out, MANIFEST_FILE) as stage:
        for src in (fit.path / "fits.parquet", fit.path / "fits.csv", fit.path / "model.json",
                    report.path / REPORT_FILE):
            if src.is_file():
                copy_file(src, stage / src.name)
        resolved = settings
        camera = Path(settings.scan.camera_spec(settings.base_dir))
        if camera.suffix.lower() == ".json" and camera.is_file():
            copy_file(camera, stage / CAMERA_FILE)
            resolved = dataclasses.replace(settings, scan=dataclasses.replace(settings.scan, camera=CAMERA_FILE))
        write_text(resolved.to_toml(), stage / SETTINGS_FILE)
        write_json(manifest, stage / MANIFEST_FILE)
    return out / "fits.parquet"


def _manifest(settings: StudySettings, out: Path, runs: list[StageRun], seconds: float) -> dict:
    stages = []
    for r in runs:
        stages.append({"name": r.name, "stage": r.stage.name, "key": r.stage.key,
                       "path": str(r.stage.path.relative_to(out)), "reused": r.reused,
                       "seconds_this_run": r.seconds, "seconds_computed": r.original_seconds, "summary": r.summary,
                       "inputs": r.stage.inputs})
    return {
        "study": to_table(settings.study),
        "source": settings.source,
        "settings": settings.to_dict(),
        "reference_distance_m": reference_distance(settings.scan.distances_m),
        "stages": stages,
        "seconds": seconds,
        "finished": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "versions": package_versions(),
        "platform": {"system": platform.platform(), "processor": platform.machine(), "cpus": os.cpu_count()},
    }
