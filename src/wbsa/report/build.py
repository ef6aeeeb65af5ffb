"""Build the report: every figure and table of a study (or a fit folder) in one self-contained HTML file.

The entry point: resolve the inputs and settings, let :class:`~wbsa.report.sections.SectionBuilder` fill the
page section by section, and write it atomically.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path

from wbsa.errors import WbsaError
from wbsa.io import write_text
from wbsa.progress import progress
from wbsa.report.data import load_report_data
from wbsa.report.sections import SectionBuilder
from wbsa.report.settings import ReportSettings
from wbsa.report.sources import ReportSources, resolve_sources
from wbsa.settings_io import from_table


@dataclass
class ReportResult:
    """What :func:`build_report` wrote.

    Attributes
    ----------
    path : Path
        The HTML file.
    figures : list of str
        Ids of the figures drawn (``fig-...``), in page order.
    tables : list of str
        Ids of the tables (``tab-...``).
    unavailable : dict
        Figure id -> why it was not drawn (data absent from the study).
    seconds : float
    """

    path: Path
    figures: list[str] = field(default_factory=list)
    tables: list[str] = field(default_factory=list)
    unavailable: dict[str, str] = field(default_factory=dict)
    seconds: float = 0.0


def report_settings_of(sources: ReportSources) -> ReportSettings:
    """The ``[report]`` settings recorded in the study's manifest, or the defaults."""
    table = sources.manifest.get("settings", {}).get("report")
    if not table:
        return ReportSettings()
    if table.get("snapshot_subject") == -1:  # manifests written before optional keys: -1 meant "not set"
        table = {k: v for k, v in table.items() if k != "snapshot_subject"}
    return from_table(ReportSettings, table, "report", str(sources.study_dir or sources.fit_dir))


def build_report(sources: ReportSources | str | os.PathLike, out: str | os.PathLike,
                 settings: ReportSettings | None = None, *, show_progress: bool | None = None) -> ReportResult:
    """Draw every figure, lay out every table and write one HTML file.

    Parameters
    ----------
    sources : ReportSources or path
        The inputs, or a study / fit folder (see :func:`wbsa.report.sources.resolve_sources`).
    out : path
        The HTML file to write (atomically).
    settings : ReportSettings, optional
        Views of the single-view figures; default: the study's ``[report]`` settings.
    show_progress : bool, optional
        Progress bar over the figures.

    Returns
    -------
    ReportResult
    """
    t0 = time.perf_counter()
    if not isinstance(sources, ReportSources):
        sources = resolve_sources(sources)
    settings = settings or report_settings_of(sources)
    data = load_report_data(sources)
    out = Path(out)
    if out.suffix.lower() not in (".html", ".htm"):
        raise WbsaError(f"report file {out} must end in .html")

    builder = SectionBuilder(data, settings)
    steps = builder.steps()
    bar = progress(total=len(steps), desc="report", unit="part", enabled=show_progress)
    for step in steps:
        step()
        bar.update(1)
    bar.close()
    seconds = time.perf_counter() - t0
    page = builder.page
    page.paragraph(f"Report built in {seconds:.1f} s.")
    write_text(page.render(), out)
    return ReportResult(path=out, figures=list(page.figures), tables=list(page.tables),
                        unavailable=dict(builder.unavailable), seconds=seconds)

