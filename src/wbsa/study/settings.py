"""Study settings: the stages' own settings, composed into one frozen record, read from TOML and checked first.

A study file has one table per stage, each the stage's own settings dataclass:

=================  ==================================================================
``[population]``   :class:`wbsa.bodies.settings.PopulationSettings`
``[scan]``         :class:`wbsa.scan.settings.ScanSettings` (one scan job per distance)
``[sensor]``       :class:`wbsa.sensor.settings.SensorSettings`
``[reconstruction]`` :class:`wbsa.surface.settings.ReconstructionSettings`
``[fit]``          :class:`wbsa.analysis.settings.FitSettings` (thresholds: ``[fit.group_spec]``)
``[report]``       :class:`wbsa.report.settings.ReportSettings`
=================  ==================================================================

plus ``[study]`` (:class:`StudyInfo`: name, description) and ``[run]`` (:class:`wbsa.parallel.RunSettings`:
how to run, never part of a stage's content address). Keys are the dataclasses' field names, read and
written by :mod:`wbsa.settings_io`: a key left out keeps its default, an optional key left out is None.

A file only lists what differs from the embedded default study, ``wbsa/configs/default.toml``, which itself
lists only what differs from the stages' defaults. Unknown tables or keys, wrong types and out-of-range
values raise a one-line :class:`~wbsa.errors.WbsaError` naming the file, the table and the key.
"""

from __future__ import annotations

import copy
import dataclasses
import os
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from wbsa.analysis.settings import FitSettings, with_vbsa_only
from wbsa.bodies.settings import PopulationSettings
from wbsa.errors import WbsaError, check_field
from wbsa.parallel import RunSettings
from wbsa.report.settings import ReportSettings
from wbsa.scan.settings import ScanJob, ScanSettings
from wbsa.sensor.settings import SensorSettings
from wbsa.settings_io import dump_toml, from_table, to_table
from wbsa.surface.settings import ReconstructionSettings
from wbsa.settings_io import check_types

#: Shipped study files (``wbsa run --config NAME``), in ``wbsa/configs/NAME.toml``.
SHIPPED_CONFIGS: tuple[str, ...] = ("default", "paper", "distance-sweep", "reconstruction", "varied")

#: Population kinds a study builds (``table`` reads a file that a stage key could not address).
STUDY_POPULATION_KINDS: tuple[str, ...] = ("random", "survey")

#: Keys of earlier study files that moved: (table, key) -> where the setting is now.
MOVED_KEYS: dict[tuple[str, str], str] = {
    ("scan", "chunk_size"): "[run] chunk_size",
    ("fit", "vbsa"): "[fit] vbsa_columns",
    ("fit", "kid_max_age_years"): "[fit.group_spec] kid_max_age_years",
    ("fit", "small_max_stature_m"): "[fit.group_spec] small_max_stature_m",
    ("fit", "big_min_stature_m"): "[fit.group_spec] big_min_stature_m",
    ("fit", "obese_min_bmi"): "[fit.group_spec] obese_min_bmi",
}


@dataclass(frozen=True)
class StudyInfo:
    """``[study]``: what the study is called (shown in the report; not part of any stage's address).

    Attributes
    ----------
    name : str
    description : str
    """

    name: str = "wbsa study"
    description: str = ""

    def __post_init__(self) -> None:
        check_types(self)


@dataclass(frozen=True, kw_only=True)
class StudySettings:
    """A whole study: the settings of every stage, as the stages define them.

    Attributes
    ----------
    study : StudyInfo
    population : PopulationSettings
        Required: a population has no default size.
    scan, sensor, reconstruction, fit, report, run
        The stages' settings (see the module doc).
    source : str
        Where the settings came from (file path or ``default``), for messages and the report.
    base_dir : str
        Folder that relative paths in the settings (a camera JSON) are read from.
    """

    study: StudyInfo = field(default_factory=StudyInfo)
    population: PopulationSettings
    scan: ScanSettings = field(default_factory=ScanSettings)
    sensor: SensorSettings = field(default_factory=SensorSettings)
    reconstruction: ReconstructionSettings = field(default_factory=ReconstructionSettings)
    fit: FitSettings = field(default_factory=FitSettings)
    report: ReportSettings = field(default_factory=ReportSettings)
    run: RunSettings = field(default_factory=RunSettings)
    source: str = "default"
    base_dir: str = "."

    def __post_init__(self) -> None:
        check_types(self)

    def __repr__(self) -> str:
        s = self.scan
        views = (f"{len(s.view_list(s.distances_m[0]))} views" if s.azimuths_deg or s.elevations_deg
                 else f"views {s.views}")
        return (f"StudySettings({self.study.name!r}: {self.population.n} {self.population.kind} subjects, camera "
                f"{s.camera}, {views}, distances {list(s.distances_m)} m, k = {self.fit.k}; from {self.source}; "
                f".to_toml() for every key)")

    def to_dict(self) -> dict[str, dict[str, Any]]:
        """The settings as TOML-ready tables (without ``source`` and ``base_dir``)."""
        return {name: to_table(getattr(self, name)) for name in SECTIONS}

    def to_toml(self) -> str:
        """The full settings as a TOML document (every key; unset optional ones as comments): it reproduces the study."""
        tables = {name: to_table(getattr(self, name), keep_none=True) for name in SECTIONS}
        if self.scan.azimuths_deg or self.scan.elevations_deg:  # the lists replace the view set: not both
            del tables["scan"]["views"]
        return dump_toml(tables, header=f"wbsa study settings (resolved from {self.source})")


#: Tables of a study file and their classes.
SECTIONS: dict[str, type] = {
    "study": StudyInfo,
    "population": PopulationSettings,
    "scan": ScanSettings,
    "sensor": SensorSettings,
    "reconstruction": ReconstructionSettings,
    "fit": FitSettings,
    "report": ReportSettings,
    "run": RunSettings,
}


def shipped_config_path(name: str) -> Path:
    """Path of a shipped study file (``default``, ``paper``, ...) inside the package."""
    if name not in SHIPPED_CONFIGS:
        raise WbsaError(f"no shipped study config {name!r}; use one of {', '.join(SHIPPED_CONFIGS)} or a .toml path")
    return Path(str(resources.files("wbsa").joinpath("configs", f"{name}.toml")))


def _read_toml(path: Path, what: str) -> dict:
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise WbsaError(f"study config {path} does not exist; give a .toml file or one of "
                        f"{', '.join(SHIPPED_CONFIGS)}") from None
    except IsADirectoryError:
        raise WbsaError(f"study config {path} is a folder; give a .toml file") from None
    except tomllib.TOMLDecodeError as exc:
        raise WbsaError(f"{what} is not valid TOML ({exc}); fix the file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise WbsaError(f"cannot read study config {path} ({type(exc).__name__}); check the file") from None


def load_settings(config: str | os.PathLike | None = None, overrides: dict | None = None) -> StudySettings:
    """Read study settings.

    Parameters
    ----------
    config : path or name, optional
        A TOML file, or the name of a shipped study (``default``, ``paper``, ``distance-sweep``,
        ``reconstruction``). ``None``: the embedded default. A file only needs the keys that differ
        from the embedded default; its ``[study]`` (name, description) is its own: a file without one is
        named after the file, with no description (never the demo's).
    overrides : dict, optional
        ``{table: {key: value}}`` laid over the file (``wbsa run --n/--views/...``), checked like it. Overrides
        of the embedded default study name it ``wbsa study`` unless they give ``[study] name``.

    Returns
    -------
    StudySettings

    Raises
    ------
    WbsaError
        Unreadable file, bad TOML, unknown table or key, wrong type or value (one line each).
    """
    default_path = shipped_config_path("default")
    base = _read_toml(default_path, "the embedded default study config")
    if config is None or str(config) == "default":
        path, user, source = default_path, {}, "default"
    else:
        text = str(config)
        path = shipped_config_path(text) if text in SHIPPED_CONFIGS else Path(text)
        user, source = _read_toml(path, str(path)), str(path)
    if user or overrides:  # the demo's title and description describe the demo only
        own = {"name": "wbsa study" if source == "default" else path.stem}
        base = {**base, "study": own}
    if overrides:
        user = merge_tables(user, overrides)
        source += " with command-line overrides"
    return settings_from_dict(merge_tables(base, user), source=source, base_dir=str(path.parent), user=user)


def merge_tables(base: dict, override: dict) -> dict:
    """``base`` with the keys of ``override`` replaced table by table (a deep copy; inputs untouched)."""
    out = copy.deepcopy(base)
    for key, value in override.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge_tables(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def settings_from_dict(tables: dict, source: str = "<dict>", base_dir: str = ".",
                       user: dict | None = None) -> StudySettings:
    """Build and check :class:`StudySettings` from TOML-like tables.

    Parameters
    ----------
    tables : dict
        ``{section: {key: value}}`` as :mod:`tomllib` returns it; ``population`` needs at least ``n``.
    source : str
        Name used in error messages.
    base_dir : str
        Folder of relative paths.
    user : dict, optional
        The user's own tables (checked first, so an unknown key is reported for the user's file).
    """
    moved = []
    for name, value in (user if user is not None else tables).items():
        if name not in SECTIONS:
            raise WbsaError(f"{source}: unknown table [{name}]; valid tables: {', '.join(SECTIONS)}")
        if not isinstance(value, dict):
            raise WbsaError(f"{source}: {name} must be a table ([{name}] with keys), not a single value")
        moved += [f"[{name}] {key} is now {MOVED_KEYS[name, key]}" for key in value if (name, key) in MOVED_KEYS]
    if moved:
        raise WbsaError(f"{source}: {', '.join(moved)}; move {'it' if len(moved) == 1 else 'them'} there")
    tables = _views_or_angles(tables, (user if user is not None else tables).get("scan", {}), source)
    sections = {name: from_table(cls, tables.get(name, {}), name, source) for name, cls in SECTIONS.items()}
    settings = StudySettings(**sections, source=source, base_dir=base_dir)
    validate_settings(settings)
    return settings


def _views_or_angles(tables: dict, user_scan: dict, source: str) -> dict:
    """``tables`` with the view set the user gave winning over inherited angle lists; both given is refused.

    ``[scan] views`` is ignored where ``azimuths_deg`` or ``elevations_deg`` is given: a user's ``views`` with
    an angle list would silently not be used, and a ``views`` given over a study with angle lists neither.
    """
    angles = [k for k in ("azimuths_deg", "elevations_deg") if user_scan.get(k)]
    if "views" in user_scan and angles:
        raise WbsaError(f"{source}: [scan] views = {user_scan['views']!r} and {' and '.join(angles)} contradict "
                        "(the angle lists replace the view set); give one of them")
    if "views" in user_scan and isinstance(tables.get("scan"), dict):
        tables = {**tables, "scan": {**tables["scan"], "azimuths_deg": [], "elevations_deg": []}}
    return tables


def validate_settings(settings: StudySettings) -> None:
    """Check what no single stage can: the stages' settings together, before any work.

    The population kind is one a study builds, the camera resolves and suits the sensor, the fit's
    predictors are population columns and its groups include ``all``.

    Raises
    ------
    WbsaError
        Naming the file and the table.
    """
    from wbsa.analysis.data import resolve_predictor
    from wbsa.bodies.table import POPULATION_COLUMNS

    src = settings.source

    def check(section: str, run) -> None:
        try:
            run()
        except WbsaError as exc:
            raise WbsaError(f"{src}: [{section}] {exc}") from None

    check("population", lambda: check_field(
        settings.population.kind in STUDY_POPULATION_KINDS, "kind",
        f"must be one of {', '.join(STUDY_POPULATION_KINDS)} in a study, got {settings.population.kind!r}"))
    camera = []
    check("scan", lambda: camera.append(settings.scan.intrinsics(settings.base_dir)))
    check("sensor", lambda: settings.sensor.check_camera(camera[0]))
    fit = fit_settings(settings)
    for name in (p for s in fit.predictor_sets for p in s):
        check("fit", lambda: resolve_predictor(name, POPULATION_COLUMNS))
    check("fit", lambda: check_field("all" in fit.groups, "groups",
                                     "must include 'all' (the report and the formulae comparison use it)"))


def scan_job(settings: StudySettings, distance_m: float) -> ScanJob:
    """The :class:`~wbsa.scan.settings.ScanJob` of one camera distance: ``[scan]``, ``[sensor]``, ``[reconstruction]``."""
    return settings.scan.job(distance_m, sensor=settings.sensor, reconstruction=settings.reconstruction,
                             base_dir=settings.base_dir)


def vbsa_columns(settings: StudySettings) -> tuple[str, ...]:
    """The VBSA selectors fitted: ``[fit] vbsa_columns`` plus one per reconstruction method."""
    cols = list(settings.fit.vbsa_columns)
    for m in settings.reconstruction.methods:
        sel = f"vbsa_recon_m2:{m}"
        if sel not in cols and f"vbsa_recon_{m.replace('-', '_')}_m2" not in cols:
            cols.append(sel)
    return tuple(cols)


def fit_settings(settings: StudySettings) -> FitSettings:
    """The ``[fit]`` settings as the study fits them.

    With the reconstruction columns added (:func:`vbsa_columns`), the VBSA-only predictor set first
    (:func:`~wbsa.analysis.settings.with_vbsa_only`) and the population's kind as ``population_kind``
    unless ``[fit]`` names one.
    """
    f = settings.fit
    return dataclasses.replace(f, vbsa_columns=vbsa_columns(settings), predictor_sets=with_vbsa_only(f.predictor_sets),
                               population_kind=f.population_kind or settings.population.kind)
