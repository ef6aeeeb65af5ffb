"""``wbsa.Study``: a whole study as one object — settings in, results folder out (the API behind ``wbsa run``)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover - for type hints only
    from wbsa.study.pipeline import StudyResult
    from wbsa.study.settings import StudySettings


@dataclass(frozen=True)
class Study:
    """A study: population → scan → fit → report, from its settings.

    Attributes
    ----------
    settings : StudySettings
        Every stage's settings (see ``wbsa run --print-config``).

    Examples
    --------
    >>> import wbsa
    >>> study = wbsa.Study.from_toml("default")
    >>> study.settings.population.n
    300
    >>> small = study.replace(population={"n": 5})
    >>> small.settings.population.n
    5
    """

    settings: StudySettings

    @classmethod
    def from_toml(cls, path: str | os.PathLike = "default") -> "Study":
        """Read a study file (only the keys that differ from the embedded default), or a shipped study by name
        (``default``, ``paper``, ``distance-sweep``, ``reconstruction``, ``varied``)."""
        from wbsa.study.settings import load_settings

        return cls(load_settings(path))

    def replace(self, **tables: dict[str, Any]) -> "Study":
        """A copy with some keys changed, table by table, e.g. ``replace(population={"n": 50})``; checked like a file."""
        from wbsa.study.settings import merge_tables, settings_from_dict

        s = self.settings
        merged = merge_tables(s.to_dict(), tables)
        return Study(settings_from_dict(merged, source=f"{s.source} (changed in Python)", base_dir=s.base_dir,
                                        user=tables))

    def to_toml(self) -> str:
        """The full settings as TOML (a file that reproduces the study)."""
        return self.settings.to_toml()

    def run(self, out: str | os.PathLike, *, workers: int | None = None, show_progress: bool | None = None,
            stream: Any = "stderr") -> StudyResult:
        """Run (or resume) the study into the folder ``out``; finished stages found there are reused.

        Parameters
        ----------
        out : path
            The study folder (created if needed); one run at a time may write it.
        workers : int, optional
            Worker processes of the population and scan stages (0 = all cores); default ``[run] workers``.
        show_progress : bool, optional
            Progress bars on stderr (default: when stderr is a terminal).
        stream : text stream, None or ``'stderr'``
            Where the one-line-per-stage log goes (None: silent).

        Returns
        -------
        StudyResult
            Paths of the report and the fit table, and what each stage did.
        """
        from wbsa.study.pipeline import run_study

        return run_study(self.settings, out, workers=workers, show_progress=show_progress, stream=stream)

    def __repr__(self) -> str:
        s = self.settings
        return (f"Study({s.study.name!r}: {s.population.n} {s.population.kind} subjects, camera {s.scan.camera}, "
                f"views {s.scan.views}, distances {list(s.scan.distances_m)} m; from {s.source})")
