"""Where a report's inputs live: a study folder, a fit stage inside one, or a plain ``wbsa fit`` folder."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

from wbsa.errors import WbsaError

#: Files that identify a study folder and a fit folder.
STUDY_MANIFEST = "study.json"
FIT_INFO = "fit_info.json"
STAGE_FILE = "stage.json"


@dataclass(frozen=True)
class ReportSources:
    """The files a report reads.

    Attributes
    ----------
    fit_dir : Path
        Folder with the outputs of ``wbsa fit`` (``fits.parquet``, ``residuals.parquet``, ...).
    population_path : Path
        Population table.
    scan_paths : tuple of Path
        Scan tables (one per camera distance in a study); their folders may hold ``intrinsics.json``.
    study_dir : Path or None
        The study folder, when there is one.
    manifest : dict
        ``study.json`` of the study (settings, stages, versions); empty without a study.
    stage_records : list of dict
        ``stage.json`` of every stage of the study, in pipeline order (run times, keys).
    """

    fit_dir: Path
    population_path: Path
    scan_paths: tuple[Path, ...]
    study_dir: Path | None = None
    manifest: dict = field(default_factory=dict)
    stage_records: list = field(default_factory=list)


def _read_json(path: Path, what: str) -> dict:
    try:
        doc = json.loads(path.read_text())
    except FileNotFoundError:
        raise WbsaError(f"{path} does not exist; {what}") from None
    except (OSError, ValueError) as exc:
        raise WbsaError(f"{path} is not readable JSON ({type(exc).__name__}); {what}") from None
    if not isinstance(doc, dict):
        raise WbsaError(f"{path} is not a JSON object; {what}")
    return doc


#: Keys of ``study.json`` a report reads, and the JSON type each must have.
_MANIFEST_TYPES = {"stages": list, "study": dict, "settings": dict, "versions": dict, "seconds": (int, float)}


def checked_manifest(doc: dict, path: Path) -> dict:
    """``study.json`` with the types a report relies on checked (it may have been edited by hand).

    Raises
    ------
    WbsaError
        One line naming the key that has the wrong type.
    """
    fix = "run the same wbsa run command again to rewrite it"
    for key, types in _MANIFEST_TYPES.items():
        if key in doc and not isinstance(doc[key], types) or isinstance(doc.get(key), bool):
            raise WbsaError(f"{path}: {key!r} has the wrong type ({type(doc[key]).__name__}); {fix}")
    for i, s in enumerate(doc.get("stages", [])):
        if not (isinstance(s, dict) and isinstance(s.get("stage"), str) and isinstance(s.get("path"), str)):
            raise WbsaError(f"{path}: stage {i} is not a record with 'stage' and 'path' names; {fix}")
    for name, table in doc.get("settings", {}).items():
        if not isinstance(table, dict):
            raise WbsaError(f"{path}: settings table {name!r} is not an object; {fix}")
    return doc


def study_sources(study_dir: str | os.PathLike) -> ReportSources:
    """The inputs of the report of a study folder (``study.json`` written by ``wbsa run``).

    Raises
    ------
    WbsaError
        No manifest, a malformed (hand-edited) manifest, or a stage folder it names is missing or
        unfinished.
    """
    study_dir = Path(study_dir)
    manifest = checked_manifest(_read_json(study_dir / STUDY_MANIFEST, "run the study with wbsa run first"),
                                study_dir / STUDY_MANIFEST)
    stages = manifest.get("stages", [])
    by_kind: dict[str, list[dict]] = {}
    for s in stages:
        by_kind.setdefault(s.get("stage", ""), []).append(s)
    if not by_kind.get("population") or not by_kind.get("scan") or not by_kind.get("fit"):
        raise WbsaError(f"{study_dir / STUDY_MANIFEST} lacks the population, scan or fit stage; run wbsa run again")
    pop = study_dir / by_kind["population"][0]["path"] / "population.parquet"
    scans = tuple(study_dir / s["path"] / "scan.parquet" for s in by_kind["scan"])
    fit_dir = study_dir / by_kind["fit"][0]["path"]
    for p in (pop, *scans, fit_dir / FIT_INFO):
        if not p.exists():
            raise WbsaError(f"{p} is missing from the study; run the same wbsa run command again to rebuild it")
    for s in (*by_kind["population"][:1], *by_kind["scan"], *by_kind["fit"][:1]):
        if not (study_dir / s["path"] / STAGE_FILE).is_file():  # the marker a stage writes last
            raise WbsaError(f"stage {study_dir / s['path']} did not finish; run the same wbsa run command again")
    records = []
    for s in stages:
        rec_path = study_dir / s["path"] / STAGE_FILE
        if rec_path.is_file():
            records.append({**_read_json(rec_path, "rerun the study"), "label": str(s.get("name", s["stage"]))})
    return ReportSources(fit_dir=fit_dir, population_path=pop, scan_paths=scans, study_dir=study_dir,
                         manifest=manifest, stage_records=records)


def fit_dir_sources(fit_dir: str | os.PathLike, population: str | os.PathLike | None = None,
                    scans: tuple[str | os.PathLike, ...] | list = ()) -> ReportSources:
    """The inputs of the report of a fit folder.

    The population and scan tables are taken from, in order: the arguments; the stage record of a fit
    stage inside a study (``stage.json``, which names the input stages); ``fit_info.json``'s
    ``inputs`` (``population``, ``scan`` paths) when the fit recorded them.

    Raises
    ------
    WbsaError
        Not a fit folder, or the inputs cannot be found.
    """
    fit_dir = Path(fit_dir)
    info = _read_json(fit_dir / FIT_INFO, "give a folder written by wbsa fit or wbsa run")
    pop = Path(population) if population else None
    scan_paths = tuple(Path(s) for s in scans)
    record = {}
    if (fit_dir / STAGE_FILE).is_file():
        record = _read_json(fit_dir / STAGE_FILE, "rerun the study")
        stages_dir = fit_dir.parent
        inputs = record.get("inputs") if isinstance(record.get("inputs"), dict) else {}
        if pop is None and isinstance(inputs.get("population"), str):
            pop = stages_dir / f"population-{inputs['population']}" / "population.parquet"
        if not scan_paths and isinstance(inputs.get("scans"), list):
            scan_paths = tuple(stages_dir / f"scan-{k}" / "scan.parquet" for k in inputs["scans"])
    recorded = info.get("inputs", {}) if isinstance(info.get("inputs"), dict) else {}
    if pop is None and isinstance(recorded.get("population"), str) and recorded["population"]:
        pop = fit_dir / recorded["population"]  # recorded relative to the fit folder (or absolute)
    if not scan_paths and isinstance(recorded.get("scan"), str) and recorded["scan"]:
        scan_paths = (fit_dir / recorded["scan"],)
    if pop is None or not scan_paths:
        raise WbsaError(f"cannot tell which population and scan tables {fit_dir} was fitted on; "
                        "give --population FILE and --scan FILE")
    for p in (pop, *scan_paths):
        if not p.is_file():
            raise WbsaError(f"input table {p} does not exist; give the population and scan tables")
    study_dir = fit_dir.parent.parent if record else None
    manifest = {}
    if study_dir is not None and (study_dir / STUDY_MANIFEST).is_file():
        manifest = checked_manifest(_read_json(study_dir / STUDY_MANIFEST, "rerun the study"),
                                    study_dir / STUDY_MANIFEST)
    return ReportSources(fit_dir=fit_dir, population_path=pop, scan_paths=scan_paths, study_dir=study_dir,
                         manifest=manifest, stage_records=[{**record, "label": "fit"}] if record else [])


def resolve_sources(path: str | os.PathLike, population: str | os.PathLike | None = None,
                    scans: tuple | list = ()) -> ReportSources:
    """A study folder (``study.json``) or a fit folder (``fit_info.json``) -> its report inputs."""
    path = Path(path)
    if not path.exists():
        raise WbsaError(f"{path} does not exist; give a study folder (wbsa run) or a fit folder (wbsa fit)")
    if not path.is_dir():
        raise WbsaError(f"{path} is a file; give a study folder (wbsa run) or a fit folder (wbsa fit)")
    if (path / STUDY_MANIFEST).is_file() and not (population or scans):
        return study_sources(path)
    if (path / FIT_INFO).is_file():
        return fit_dir_sources(path, population, scans)
    if (path / STUDY_MANIFEST).is_file():
        src = study_sources(path)
        return ReportSources(fit_dir=src.fit_dir, population_path=Path(population) if population else src.population_path,
                             scan_paths=tuple(Path(s) for s in scans) or src.scan_paths, study_dir=src.study_dir,
                             manifest=src.manifest, stage_records=src.stage_records)
    raise WbsaError(f"{path} is neither a study folder (no {STUDY_MANIFEST}) nor a fit folder (no {FIT_INFO}); "
                    "give the --out folder of wbsa run or wbsa fit")
