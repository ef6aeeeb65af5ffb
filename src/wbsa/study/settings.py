"""Study settings: a frozen dataclass tree read from TOML and checked before any work starts.

A study file has one table per stage (``[population]``, ``[scan]``, ``[sensor]``, ``[reconstruction]``,
``[fit]``, ``[report]``) plus ``[study]`` (name, description) and ``[run]`` (how to run: workers; never
part of a stage's content address). A file only lists what differs from the embedded default,
``wbsa/configs/default.toml``: every key it leaves out keeps the default's value. Unknown tables or
keys, wrong types and out-of-range values raise a one-line :class:`~wbsa.errors.WbsaError` naming the
file, the table and the key.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import os
import tomllib
import types
import typing
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, Literal, Union, get_args, get_origin

from wbsa.errors import WbsaError

#: Columns of the pinned population table that can be extra predictors (``sex`` via the alias ``sex``).
POPULATION_TABLE_COLUMNS: tuple[str, ...] = (
    "sex", "age_years", "stature_m", "mass_kg", "bmi", "volume_m3", "waist_circ_m", "hip_circ_m", "bust_circ_m",
    "underbust_circ_m", "neck_circ_m", "upper_arm_circ_m", "thigh_circ_m", "front_chest_width_m")

#: Shipped study files (``wbsa run --config NAME``), in ``wbsa/configs/NAME.toml``.
SHIPPED_CONFIGS: tuple[str, ...] = ("default", "paper", "distance-sweep", "reconstruction", "varied")

PopulationKind = Literal["random", "survey"]
DensityModel = Literal["constant", "deurenberg-siri", "deurenberg-brozek"]
Sampling = Literal["paper", "varied"]
NoiseModel = Literal["none", "nguyen2012"]
ReconstructionMethod = Literal["grid", "ball-pivoting", "poisson"]
ModelKind = Literal["linear", "quadratic", "loglog", "wls"]
GroupName = Literal["all", "males", "females", "kids", "adults", "small", "normal", "big", "obese"]


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


@dataclass(frozen=True)
class PopulationConfig:
    """``[population]``: the virtual population (:func:`wbsa.bodies.build.build_population`).

    Attributes
    ----------
    kind : {'random', 'survey'}
        ``random`` is the paper's Virtual Random, ``survey`` its Virtual NHANES.
    n : int
        Subjects (random) or survey people (survey), >= 1.
    seed : int
        Seed of the parameter draw, >= 0.
    density_kg_m3 : float
        Body density for mass = volume × density (``density_model = "constant"``).
    density_model : {'constant', 'deurenberg-siri', 'deurenberg-brozek'}
        ``constant`` (the paper's tables, anny's 980 kg/m³) or each body's density from its fat
        fraction (:mod:`wbsa.bodies.composition`).
    sampling : {'paper', 'varied'}
        (random) ``paper``: the paper's uniform macro parameters; ``varied``: local changes, anny's
        whole range, an obese half of the adults, ages 7–80 (``docs/population.md``).
    variations : int
        (survey) weight/muscle variations per person, >= 0.
    """

    kind: PopulationKind = "random"
    n: int = 300
    seed: int = 0
    density_kg_m3: float = 980.0
    density_model: DensityModel = "constant"
    sampling: Sampling = "paper"
    variations: int = 0

    def __post_init__(self) -> None:
        _check(self.n >= 1, "n", f"must be at least 1, got {self.n}")
        _check(self.seed >= 0, "seed", f"must be 0 or more, got {self.seed}")
        _check(math.isfinite(self.density_kg_m3) and 500 <= self.density_kg_m3 <= 2000, "density_kg_m3",
               f"must be a body density in 500–2000 kg/m³, got {self.density_kg_m3:g}")
        _check(self.variations >= 0, "variations", f"must be 0 or more, got {self.variations}")


@dataclass(frozen=True)
class ScanConfig:
    """``[scan]``: the virtual depth camera and where it stands (:class:`wbsa.scan.settings.ScanSettings`).

    Attributes
    ----------
    camera : str
        Preset (``kinect-v1``, ``kinect-v2``, ``tum``) or the path of an Open3D intrinsics JSON file
        (relative paths are read from the study file's folder).
    views : str
        View set: ``paper`` (the 65 views), ``front``, ``sphere:N``, ``grid:STEP``. Ignored when
        ``azimuths_deg`` or ``elevations_deg`` is given.
    azimuths_deg, elevations_deg : tuple of float
        Instead of ``views``: the product of these angle lists (empty = use ``views``).
    distances_m : tuple of float
        Camera distances; each is scanned as its own stage and fitted as its own views (the paper: 4.3 m,
        with 3.5–5 m in its S1 file). Several distances make the report show their effect.
    seed : int
        Root seed of the per-subject sensor noise.
    chunk_size : int
        Subjects per chunk (the unit of parallel work and of resuming).
    """

    camera: str = "kinect-v1"
    views: str = "paper"
    azimuths_deg: tuple[float, ...] = ()
    elevations_deg: tuple[float, ...] = ()
    distances_m: tuple[float, ...] = (4.3,)
    seed: int = 0
    chunk_size: int = 25

    def __post_init__(self) -> None:
        _check(len(self.distances_m) >= 1, "distances_m", "needs at least one distance, e.g. [4.3]")
        for d in self.distances_m:
            _check(math.isfinite(d) and d > 0, "distances_m", f"must be positive distances in metres, got {d:g}")
        _check(len(set(self.distances_m)) == len(self.distances_m), "distances_m", "lists a distance twice")
        _check(self.seed >= 0, "seed", f"must be 0 or more, got {self.seed}")
        _check(self.chunk_size >= 1, "chunk_size", f"must be at least 1, got {self.chunk_size}")
        for name in ("azimuths_deg", "elevations_deg"):
            for a in getattr(self, name):
                _check(math.isfinite(a), name, f"must be finite angles in degrees, got {a}")


@dataclass(frozen=True)
class SensorConfig:
    """``[sensor]``: the simulated depth sensor (:class:`wbsa.sensor.SensorModel`); all off by default.

    Attributes
    ----------
    noise : {'none', 'nguyen2012'}
    lateral_noise, quantise, range_limits : bool
    holes_fraction, pixel_dropout : float
        Fractions in [0, 1].
    grazing_dropout_deg : float
        Degrees in [0, 90); negative (the default, -1) means the sensor model's own default.
    """

    noise: NoiseModel = "none"
    lateral_noise: bool = True
    quantise: bool = False
    holes_fraction: float = 0.0
    pixel_dropout: float = 0.0
    grazing_dropout_deg: float = -1.0
    range_limits: bool = False

    def __post_init__(self) -> None:
        for name in ("holes_fraction", "pixel_dropout"):
            v = getattr(self, name)
            _check(0.0 <= v <= 1.0, name, f"must be a fraction in [0, 1], got {v:g}")
        _check(self.grazing_dropout_deg < 90.0, "grazing_dropout_deg",
               f"must be below 90 degrees (negative: the model's default), got {self.grazing_dropout_deg:g}")


@dataclass(frozen=True)
class ReconstructionConfig:
    """``[reconstruction]``: surface reconstruction methods; each adds a ``vbsa_recon_<method>_m2`` column.

    Attributes
    ----------
    methods : tuple of {'grid', 'ball-pivoting', 'poisson'}
        Empty: no reconstruction.
    """

    methods: tuple[ReconstructionMethod, ...] = ()

    def __post_init__(self) -> None:
        _check(len(set(self.methods)) == len(self.methods), "methods", "lists a method twice")


@dataclass(frozen=True)
class FitConfig:
    """``[fit]``: the per-view regressions (:class:`wbsa.analysis.fit_views.FitSettings`).

    Attributes
    ----------
    vbsa : tuple of str
        VBSA columns fitted (``vbsa_visible_m2``, ``vbsa_hit_m2``); the reconstruction columns of
        ``[reconstruction] methods`` are added automatically.
    predictor_sets : tuple of tuple of str
        Extra predictors besides VBSA, one fit per set; ``[]`` (VBSA only) is always fitted.
    models : tuple of {'linear', 'quadratic', 'loglog', 'wls'}
        The first one is the model of the report's figures.
    groups : tuple of str
        Groups fitted on their own.
    k : int
        Cross-validation folds (paper: 10).
    seed : int
        Seed of the fold assignment.
    kid_max_age_years, small_max_stature_m, big_min_stature_m, obese_min_bmi : float
        Group thresholds.
    require_in_frame : bool
        Leave out views where the body is cut by the image border.
    correlation_view_deg : (float, float)
        Azimuth and elevation of the Spearman correlation matrix (paper Table 2: 0, 0).
    residual_groups, residual_models : tuple of str
        Fits whose per-subject residuals are kept.
    """

    vbsa: tuple[str, ...] = ("vbsa_visible_m2",)
    predictor_sets: tuple[tuple[str, ...], ...] = ((), ("stature_m",))
    models: tuple[ModelKind, ...] = ("linear", "loglog", "wls")
    groups: tuple[GroupName, ...] = ("all", "males", "females", "kids", "adults", "small", "normal", "big")
    k: int = 10
    seed: int = 0
    kid_max_age_years: float = 15.0
    small_max_stature_m: float = 1.40
    big_min_stature_m: float = 2.00
    obese_min_bmi: float = 30.0
    require_in_frame: bool = True
    correlation_view_deg: tuple[float, float] = (0.0, 0.0)
    residual_groups: tuple[GroupName, ...] = ("all",)
    residual_models: tuple[ModelKind, ...] = ("linear",)

    def __post_init__(self) -> None:
        _check(self.k >= 2, "k", f"must be at least 2 folds, got {self.k}")
        _check(len(self.vbsa) >= 1, "vbsa", "needs at least one VBSA column, e.g. ['vbsa_visible_m2']")
        _check(len(self.models) >= 1, "models", "needs at least one model, e.g. ['linear']")
        _check(len(self.groups) >= 1, "groups", "needs at least one group, e.g. ['all']")
        _check("all" in self.groups, "groups", "must include 'all' (the report and the formulae comparison use it)")


@dataclass(frozen=True)
class ReportConfig:
    """``[report]``: which views the report's single-view figures show.

    Attributes
    ----------
    scatter_view_deg : (float, float)
        View of the VBSA–WBSA scatter and the residual plots (paper Fig 10, S1, S2: 0, 0).
    nonlinear_view_deg : (float, float)
        View of the non-linearity figure (paper Fig 16: 60, 60).
    snapshot_view_deg : (float, float)
        View whose point cloud the snapshots show (paper Fig 8: 60, 60).
    snapshot_subject : int
        Subject of the snapshots; -1 picks the subject with the median WBSA.
    dpi : int
        Resolution of the figures.
    """

    scatter_view_deg: tuple[float, float] = (0.0, 0.0)
    nonlinear_view_deg: tuple[float, float] = (60.0, 60.0)
    snapshot_view_deg: tuple[float, float] = (60.0, 60.0)
    snapshot_subject: int = -1
    dpi: int = 100

    def __post_init__(self) -> None:
        _check(30 <= self.dpi <= 600, "dpi", f"must be in 30–600, got {self.dpi}")
        _check(self.snapshot_subject >= -1, "snapshot_subject", f"must be a subject id or -1, got {self.snapshot_subject}")


@dataclass(frozen=True)
class RunConfig:
    """``[run]``: how to run (never changes results, so never part of a stage's address).

    Attributes
    ----------
    workers : int
        Scan worker processes; 0 = all cores, 1 = in this process (no dask).
    scheduler : str
        Address of an existing dask scheduler (empty: a local cluster).
    """

    workers: int = 0
    scheduler: str = ""

    def __post_init__(self) -> None:
        _check(self.workers >= 0, "workers", f"must be 0 (all cores) or more, got {self.workers}")


@dataclass(frozen=True)
class StudySettings:
    """A whole study: one frozen record per stage.

    Attributes
    ----------
    study, population, scan, sensor, reconstruction, fit, report, run
        See the section classes.
    source : str
        Where the settings came from (file path or ``default``), for messages and the report.
    base_dir : str
        Folder that relative paths in the settings (a camera JSON) are read from.
    """

    study: StudyInfo = field(default_factory=StudyInfo)
    population: PopulationConfig = field(default_factory=PopulationConfig)
    scan: ScanConfig = field(default_factory=ScanConfig)
    sensor: SensorConfig = field(default_factory=SensorConfig)
    reconstruction: ReconstructionConfig = field(default_factory=ReconstructionConfig)
    fit: FitConfig = field(default_factory=FitConfig)
    report: ReportConfig = field(default_factory=ReportConfig)
    run: RunConfig = field(default_factory=RunConfig)
    source: str = "default"
    base_dir: str = "."

    def to_dict(self) -> dict[str, dict[str, Any]]:
        """The settings as TOML-ready tables (without ``source`` and ``base_dir``)."""
        return {name: _plain(getattr(self, name)) for name in SECTIONS}

    def to_toml(self) -> str:
        """The full settings as a TOML document (every key, so the file reproduces the study)."""
        return dump_toml(self.to_dict(), header=f"wbsa study settings (resolved from {self.source})")


#: Tables of a study file and their classes.
SECTIONS: dict[str, type] = {
    "study": StudyInfo,
    "population": PopulationConfig,
    "scan": ScanConfig,
    "sensor": SensorConfig,
    "reconstruction": ReconstructionConfig,
    "fit": FitConfig,
    "report": ReportConfig,
    "run": RunConfig,
}


class _FieldError(Exception):
    """A bad value in one field; turned into a WbsaError naming the file and the table."""

    def __init__(self, key: str, message: str) -> None:
        super().__init__(message)
        self.key = key


def _check(ok: bool, key: str, message: str) -> None:
    if not ok:
        raise _FieldError(key, message)


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


def load_settings(config: str | os.PathLike | None = None) -> StudySettings:
    """Read study settings.

    Parameters
    ----------
    config : path or name, optional
        A TOML file, or the name of a shipped study (``default``, ``paper``, ``distance-sweep``,
        ``reconstruction``). ``None``: the embedded default. A file only needs the keys that differ
        from the embedded default.

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
        return settings_from_dict(base, source="default", base_dir=str(default_path.parent))
    text = str(config)
    path = shipped_config_path(text) if text in SHIPPED_CONFIGS else Path(text)
    user = _read_toml(path, str(path))
    return settings_from_dict(merge_tables(base, user), source=str(path), base_dir=str(path.parent),
                              user=user)


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
        ``{section: {key: value}}`` as :mod:`tomllib` returns it.
    source : str
        Name used in error messages.
    base_dir : str
        Folder of relative paths.
    user : dict, optional
        The user's own tables (checked first, so an unknown key is reported for the user's file).
    """
    for name, value in (user if user is not None else tables).items():
        if name not in SECTIONS:
            raise WbsaError(f"{source}: unknown table [{name}]; valid tables: {', '.join(SECTIONS)}")
        if not isinstance(value, dict):
            raise WbsaError(f"{source}: {name} must be a table ([{name}] with keys), not a single value")
    sections = {}
    for name, cls in SECTIONS.items():
        sections[name] = _build(cls, tables.get(name, {}), name, source)
    settings = StudySettings(**sections, source=source, base_dir=base_dir)
    validate_settings(settings)
    return settings


def section_from_table(cls: type, table: dict, section: str, source: str = "<dict>"):
    """One settings table (e.g. ``[report]``) as its dataclass, checked like a study file's."""
    return _build(cls, table, section, source)


def _build(cls: type, table: dict, section: str, source: str):
    hints = typing.get_type_hints(cls)
    names = [f.name for f in dataclasses.fields(cls)]
    unknown = [k for k in table if k not in names]
    if unknown:
        raise WbsaError(f"{source}: unknown key {unknown[0]!r} in [{section}]; valid keys: {', '.join(names)}")
    kwargs = {}
    for key, value in table.items():
        try:
            kwargs[key] = _coerce(value, hints[key])
        except _FieldError as exc:
            raise WbsaError(f"{source}: [{section}] {key} {exc}") from None
    try:
        return cls(**kwargs)
    except _FieldError as exc:
        raise WbsaError(f"{source}: [{section}] {exc.key} {exc}") from None


def _type_name(tp: Any) -> str:
    origin = get_origin(tp)
    if origin is Literal:
        return "one of " + ", ".join(repr(a) for a in get_args(tp))
    if origin is tuple:
        args = get_args(tp)
        if len(args) == 2 and args[1] is Ellipsis:
            return f"a list of {_type_name(args[0])}"
        return f"a list of {len(args)} values ({', '.join(_type_name(a) for a in args)})"
    return {bool: "true or false", int: "an integer", float: "a number", str: "a string"}.get(tp, str(tp))


def _coerce(value: Any, tp: Any) -> Any:
    """``value`` (from TOML) as type ``tp``; raises :class:`_FieldError` with 'must be ...'."""
    origin = get_origin(tp)
    if origin in (Union, types.UnionType):
        args = [a for a in get_args(tp) if a is not type(None)]
        return _coerce(value, args[0])
    bad = _FieldError("", f"must be {_type_name(tp)}, got {value!r}")
    if origin is Literal:
        if value not in get_args(tp):
            raise bad
        return value
    if origin is tuple:
        if not isinstance(value, list):
            raise bad
        args = get_args(tp)
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_coerce(v, args[0]) for v in value)
        if len(value) != len(args):
            raise bad
        return tuple(_coerce(v, a) for v, a in zip(value, args))
    if tp is bool:
        if not isinstance(value, bool):
            raise bad
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise bad
        return value
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise bad
        return float(value)
    if tp is str:
        if not isinstance(value, str):
            raise bad
        return value
    raise bad  # pragma: no cover - every field type is handled above


def validate_settings(settings: StudySettings) -> None:
    """Check the settings against the stages' own rules (camera, views, sensor, fit) before any work.

    Raises
    ------
    WbsaError
        Naming the file and the table.
    """
    src = settings.source
    try:
        scan_settings(settings, settings.scan.distances_m[0])
    except WbsaError as exc:
        raise WbsaError(f"{src}: [scan]/[sensor]/[reconstruction] {exc}") from None
    try:
        fit_settings(settings)
    except WbsaError as exc:
        raise WbsaError(f"{src}: [fit] {exc}") from None


def camera_spec(settings: StudySettings) -> str:
    """The ``[scan] camera`` value with a relative JSON path made absolute (from the study file's folder)."""
    cam = settings.scan.camera
    from wbsa.camera.intrinsics import PRESETS

    if cam in PRESETS or not (cam.lower().endswith(".json") or "/" in cam or os.sep in cam):
        return cam  # a preset name (an unknown one gets the camera stage's "unknown preset" message)
    path = Path(cam)
    if not path.is_absolute():
        path = Path(settings.base_dir) / path
    return str(path)


def sensor_model(settings: StudySettings):
    """The :class:`wbsa.sensor.SensorModel` of ``[sensor]``, or None when it changes nothing."""
    s = settings.sensor
    from wbsa.sensor.model import SensorModel

    model = SensorModel(noise=s.noise, lateral_noise=s.lateral_noise, quantise=s.quantise,
                        holes_fraction=s.holes_fraction, pixel_dropout=s.pixel_dropout,
                        grazing_dropout_deg=None if s.grazing_dropout_deg < 0 else s.grazing_dropout_deg,
                        range_limits=s.range_limits)
    return None if model.is_ideal else model


def scan_settings(settings: StudySettings, distance_m: float):
    """The :class:`wbsa.scan.settings.ScanSettings` of one camera distance."""
    from wbsa.camera.intrinsics import resolve_camera
    from wbsa.camera.views import parse_views
    from wbsa.scan.settings import ScanSettings

    sc = settings.scan
    camera = resolve_camera(camera_spec(settings))
    if sc.azimuths_deg or sc.elevations_deg:
        views = parse_views(None, azimuths=list(sc.azimuths_deg) or None, elevations=list(sc.elevations_deg) or None,
                            distance_m=distance_m)
    else:
        views = parse_views(sc.views, distance_m=distance_m)
    return ScanSettings(camera=camera, views=tuple(views), sensor=sensor_model(settings),
                        reconstruct=tuple(settings.reconstruction.methods), seed=sc.seed, chunk_size=sc.chunk_size)


def vbsa_columns(settings: StudySettings) -> tuple[str, ...]:
    """The VBSA selectors fitted: ``[fit] vbsa`` plus one per reconstruction method."""
    cols = list(settings.fit.vbsa)
    for m in settings.reconstruction.methods:
        sel = f"vbsa_recon_m2:{m}"
        if sel not in cols and f"vbsa_recon_{m.replace('-', '_')}_m2" not in cols:
            cols.append(sel)
    return tuple(cols)


def fit_settings(settings: StudySettings):
    """The :class:`wbsa.analysis.fit_views.FitSettings` of ``[fit]``."""
    from wbsa.analysis.fit_views import FitSettings
    from wbsa.analysis.groups import GroupSpec

    from wbsa.analysis.data import resolve_predictor, resolve_vbsa_column

    f = settings.fit
    for col in vbsa_columns(settings):
        resolve_vbsa_column(col)
    sets = tuple(dict.fromkeys([(), *(tuple(s) for s in f.predictor_sets)]))
    for name in (p for s in sets for p in s):
        resolve_predictor(name, POPULATION_TABLE_COLUMNS)
    return FitSettings(
        vbsa_columns=vbsa_columns(settings),
        predictor_sets=sets,
        models=tuple(f.models),
        groups=tuple(f.groups),
        group_spec=GroupSpec(kid_max_age_years=f.kid_max_age_years, small_max_stature_m=f.small_max_stature_m,
                             big_min_stature_m=f.big_min_stature_m, obese_min_bmi=f.obese_min_bmi),
        k=f.k,
        seed=f.seed,
        require_in_frame=f.require_in_frame,
        residual_groups=tuple(f.residual_groups),
        residual_models=tuple(f.residual_models),
        population_kind=settings.population.kind,
    )


def _plain(obj: Any) -> Any:
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: _plain(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, tuple):
        return [_plain(v) for v in obj]
    return obj


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else ("inf" if v > 0 else "-inf") if not math.isnan(v) else "nan"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {type(v).__name__} as TOML")


def dump_toml(tables: dict[str, dict[str, Any]], header: str = "") -> str:
    """Write ``{table: {key: value}}`` (scalars and lists only) as TOML text that :mod:`tomllib` reads back."""
    lines = [f"# {header}", ""] if header else []
    for name, table in tables.items():
        lines.append(f"[{name}]")
        lines += [f"{k} = {_toml_value(v)}" for k, v in table.items()]
        lines.append("")
    return "\n".join(lines)
