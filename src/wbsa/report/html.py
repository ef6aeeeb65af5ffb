"""A self-contained HTML page: figures embedded as base64 PNG, tables as HTML, inline CSS, no scripts."""

from __future__ import annotations

import base64
import html
import io
import re
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

CSS = """
body { font-family: -apple-system, 'Segoe UI', Helvetica, Arial, sans-serif; margin: 2em auto; max-width: 1200px;
       padding: 0 1em; color: #222; line-height: 1.45; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; } h2 { border-bottom: 1px solid #ccc; padding-bottom: 0.2em; margin-top: 2em; }
figure { margin: 1.5em 0; } figure img { max-width: 100%; height: auto; border: 1px solid #eee; }
figcaption { font-size: 0.9em; color: #444; margin-top: 0.4em; }
table.data { border-collapse: collapse; font-size: 0.8em; margin: 0.8em 0; }
table.data th, table.data td { border: 1px solid #ddd; padding: 2px 6px; text-align: right; }
table.data th { background: #f3f3f3; } table.data td:first-child, table.data th:first-child { text-align: left; }
.table-box { max-width: 100%; overflow-x: auto; }
.scroll { max-height: 32em; overflow: auto; display: inline-block; }
p.na { color: #a33; font-style: italic; } .meta { color: #666; font-size: 0.9em; }
nav ul { columns: 2; font-size: 0.9em; } code { background: #f5f5f5; padding: 0 3px; }
ul.claims li { margin: 0.3em 0; } table.nowrap td { white-space: nowrap; }
@media print {
  body { max-width: none; margin: 0; font-size: 10pt; }
  .scroll { max-height: none; overflow: visible; display: block; } .table-box { overflow: visible; }
  table.data { font-size: 8pt; } table.data thead { display: table-header-group; }
  table.data tr, figure { page-break-inside: avoid; break-inside: avoid; }
  nav { display: none; }
}
"""


def png_bytes(fig, dpi: int | None = None) -> bytes:
    """Render a matplotlib figure to PNG bytes (Agg)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi or fig.dpi)
    return buf.getvalue()


def format_table(df: pd.DataFrame, digits: int = 4) -> pd.DataFrame:
    """A copy with floats written to ``digits`` significant digits and NaN as an empty cell."""
    out = df.copy()
    for c in out.columns:
        col = out[c]
        if pd.api.types.is_float_dtype(col):
            out[c] = [("" if not np.isfinite(v) else f"{v:.{digits}g}") for v in col.to_numpy(float)]
        elif pd.api.types.is_bool_dtype(col):
            out[c] = col.map({True: "yes", False: "no"})
        else:
            out[c] = col.map(lambda v: "" if v is None or (isinstance(v, float) and np.isnan(v)) else v)
    return out


@dataclass
class Page:
    """Builder of the report page: sections of text, figures and tables, in order."""

    title: str
    subtitle: str = ""
    parts: list[str] = field(default_factory=list)
    toc: list[tuple[str, str]] = field(default_factory=list)
    figures: list[str] = field(default_factory=list)
    tables: list[str] = field(default_factory=list)
    _n_fig: int = 0
    _n_tab: int = 0

    def section(self, anchor: str, title: str, text: str = "") -> None:
        """Start a section (``<h2 id=anchor>``) with an optional paragraph."""
        self.toc.append((anchor, title))
        self.parts.append(f'<h2 id="{html.escape(anchor)}">{html.escape(title)}</h2>')
        if text:
            self.paragraph(text)

    def paragraph(self, text: str, raw: bool = False) -> None:
        """A paragraph (escaped unless ``raw``)."""
        self.parts.append(f"<p>{text if raw else html.escape(text)}</p>")

    def bullets(self, items: list[str]) -> None:
        """A bulleted list of plain (escaped) sentences."""
        lis = "".join(f"<li>{html.escape(t)}</li>" for t in items)
        self.parts.append(f'<ul class="claims">{lis}</ul>')

    def figure(self, fig_id: str, png: bytes, caption: str) -> None:
        """An embedded PNG figure with a numbered caption."""
        self._n_fig += 1
        data = base64.b64encode(png).decode("ascii")
        self.figures.append(fig_id)
        self.parts.append(
            f'<figure id="{html.escape(fig_id)}"><img alt="{html.escape(caption[:120])}" '
            f'src="data:image/png;base64,{data}"><figcaption><b>Figure {self._n_fig}.</b> '
            f"{html.escape(caption)}</figcaption></figure>")

    def unavailable(self, fig_id: str, what: str, reason: str) -> None:
        """A note in place of a figure whose data the study does not have."""
        self.parts.append(f'<p class="na" id="{html.escape(fig_id)}-na">{html.escape(what)}: not drawn, '
                          f"{html.escape(reason)}.</p>")

    def table(self, tab_id: str, df: pd.DataFrame, caption: str, digits: int = 4, scroll: bool = False,
              nowrap: bool = False) -> None:
        """A table with a numbered caption; floats to ``digits`` significant digits.

        Every table sits in a box as wide as the page at most: a table wider than that scrolls sideways inside
        its box, never the page. Column names may break after an underscore (``<wbr>``), so a table of many
        ``snake_case`` columns narrows to the page first. ``scroll`` also caps the box's height on screen
        (printed in full); ``nowrap`` keeps each body cell on one line.
        """
        self._n_tab += 1
        self.tables.append(tab_id)
        classes = "data nowrap" if nowrap else "data"
        body = format_table(df, digits).to_html(index=False, table_id=tab_id, classes=classes, border=0, escape=True,
                                               na_rep="")
        body = re.sub(r"(<th(?:\s[^>]*)?>)(.*?)(</th>)", lambda m: m[1] + m[2].replace("_", "_<wbr>") + m[3], body,
                      flags=re.S)
        cap = f"<p><b>Table {self._n_tab}.</b> {html.escape(caption)}</p>"
        box = "table-box scroll" if scroll else "table-box"
        self.parts.append(cap + f'<div class="{box}">{body}</div>')

    def render(self) -> str:
        """The whole page as one HTML string."""
        nav = "".join(f'<li><a href="#{html.escape(a)}">{html.escape(t)}</a></li>' for a, t in self.toc)
        return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                f"<title>{html.escape(self.title)}</title><style>{CSS}</style></head><body>"
                f"<h1>{html.escape(self.title)}</h1><p class=\"meta\">{html.escape(self.subtitle)}</p>"
                f"<nav><ul>{nav}</ul></nav>" + "\n".join(self.parts) + "</body></html>\n")
