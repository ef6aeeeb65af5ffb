"""Every settings class of wbsa is checked by the one check (:func:`wbsa.settings_io.check_types`): a value of the
wrong type is a one-line :class:`~wbsa.errors.SettingsError` naming its field, from Python as from TOML."""

from __future__ import annotations

import dataclasses
import importlib
import re
import typing
from pathlib import Path

import pytest

from wbsa.errors import SettingsError

SRC = Path(__file__).resolve().parents[1] / "src"
#: The settings classes: every ``...Settings`` and the tables ``StudyInfo``, ``StartGrid`` and ``GroupSpec``.
SETTINGS_NAME = re.compile(r"^class (\w+Settings|StudyInfo|StartGrid|GroupSpec)\b", re.M)
#: A value of the wrong type for a field of each plain type (a bool is not an int, a string is not a number).
WRONG = {bool: "yes", int: True, float: "0.03", str: 3}
#: Required fields (no default) of the classes that have them.
REQUIRED = {"RandomPopulationSettings": {"n": 10}, "PopulationSettings": {"n": 10}}


def settings_classes() -> list[type]:
    found = []
    for path in sorted((SRC / "wbsa").rglob("*.py")):
        for name in SETTINGS_NAME.findall(path.read_text()):
            module = importlib.import_module(".".join(path.relative_to(SRC).with_suffix("").parts))
            cls = getattr(module, name)
            if dataclasses.is_dataclass(cls):
                found.append(cls)
    return found


def wrong_value(tp):
    """A value of the wrong type for a field of type ``tp``, or None where none is made here."""
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin is typing.Literal:
        return "no-such-choice"
    if origin is tuple:
        inner = [wrong_value(a) for a in (args[:1] if len(args) == 2 and args[1] is Ellipsis else args)]
        return None if any(v is None for v in inner) else tuple(inner)
    if origin is typing.Union or type(tp).__name__ == "UnionType":
        plain = [a for a in args if a is not type(None)]
        return wrong_value(plain[0]) if len(plain) == 1 else None
    return WRONG.get(tp)


def _default(cls):
    if cls.__name__ == "StudySettings":
        from wbsa.bodies.settings import PopulationSettings

        return cls(population=PopulationSettings(n=10))
    return cls(**REQUIRED.get(cls.__name__, {}))


def test_the_walk_finds_the_settings_classes():
    names = {cls.__name__ for cls in settings_classes()}
    assert {"BodyFitSettings", "SegmentSettings", "TrainSettings", "CaptureSettings", "StudySettings",
            "MatchSettings", "ClaimSettings", "RoomTestSettings", "SensorSettings"} <= names


@pytest.mark.parametrize("cls", settings_classes(), ids=lambda cls: cls.__name__)
def test_every_settings_class_refuses_a_value_of_the_wrong_type_naming_the_field(cls):
    default = _default(cls)
    hints = typing.get_type_hints(cls)
    checked = 0
    for f in dataclasses.fields(cls):
        wrong = wrong_value(hints[f.name])
        if wrong is None or not f.init:
            continue
        with pytest.raises(SettingsError) as err:
            dataclasses.replace(default, **{f.name: wrong})
        assert err.value.field == f.name and "\n" not in str(err.value), str(err.value)
        checked += 1
    assert checked or cls.__name__ in {"StudySettings"}, f"{cls.__name__} has no plain field to check"


def test_the_cases_the_issue_names():
    from wbsa.estimation.methods.body_fit.settings import BodyFitSettings
    from wbsa.estimation.subject.settings import SegmentSettings

    for kwargs, message in ((dict(steps=True), "steps must be an integer, got True"),
                            (dict(local_changes="no"), "local_changes must be true or false, got 'no'")):
        with pytest.raises(SettingsError, match=message):
            BodyFitSettings(**kwargs)
    with pytest.raises(SettingsError, match="voxel_m must be a number, got '0.03'"):
        SegmentSettings(voxel_m="0.03")
    assert SegmentSettings(pick=(3, 4)).pick == (3, 4) and SegmentSettings(pick="center").pick == "center"
