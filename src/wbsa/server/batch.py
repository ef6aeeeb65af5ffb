"""Batches of ``wbsa serve``: several depth files, one row each (WBSA, interval, flags), a CSV and progress.

A batch runs its files one after another in one worker thread (so a batch never holds more than one of the
runner's places), each through :func:`wbsa.server.jobs.measure`, the path of a single upload; a file that
cannot be measured is a row with its error, and the batch goes on.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass, field

from wbsa.server.uploads import Upload, UploadError, check_depth_upload

#: The CSV's columns, in order.
CSV_COLUMNS = ("file", "wbsa_m2", "wbsa_lo_m2", "wbsa_hi_m2", "level", "method", "camera", "clothes", "clothing_m",
               "clothing_sd_m", "clothing_stated", "stature_stated_m", "flags", "error")


@dataclass
class Batch:
    """One batch: its files, the rows done so far and whether it has ended."""

    id: str
    names: list[str]
    rows: list[dict] = field(default_factory=list)
    done: bool = False

    def progress(self) -> dict:
        """JSON for the page: how many of how many, the rows so far, and the CSV's address once done."""
        return {"id": self.id, "total": len(self.names), "done_count": len(self.rows), "done": self.done,
                "rows": list(self.rows), "csv": f"api/batch/{self.id}.csv" if self.done else None}

    def csv_bytes(self) -> bytes:
        """The rows as CSV (UTF-8), one line per file, flags as their names joined by ``;``."""
        buf = io.StringIO()
        writer = csv.DictWriter(buf, fieldnames=CSV_COLUMNS, extrasaction="ignore", lineterminator="\n")
        writer.writeheader()
        for row in self.rows:
            writer.writerow({**row, "flags": ";".join(row.get("flags", ()))})
        return buf.getvalue().encode("utf-8")


def row_of(result) -> dict:
    """A batch row from a :class:`wbsa.server.jobs.Result`."""
    a = result.answer
    if "error" in a:
        return {"file": result.name, "error": a["error"], "flags": [], "result": result.id}
    stated = {k: a["estimate"][k] for k in ("clothes", "clothing_m", "clothing_sd_m", "clothing_stated",
                                            "stature_stated_m")}  # what was stated, or that nothing was
    return {"file": result.name, "wbsa_m2": a["wbsa_m2"], "wbsa_lo_m2": a["wbsa_lo_m2"], "wbsa_hi_m2": a["wbsa_hi_m2"],
            "level": a["level"], "method": a["method"], "camera": a["camera"], **stated,
            "flags": [f["name"] for f in a["flags"]], "error": "", "result": result.id}


def run_batch(batch: Batch, uploads: list[Upload], options, model, root, store) -> None:
    """Measure every upload of ``batch`` in turn, adding a row (and the result to ``store``) after each."""
    from wbsa.server.jobs import Result, internal_error, measure, new_id

    try:
        for upload in uploads:
            try:
                check_depth_upload(upload)
                result = measure(upload, options, model, root)
            except UploadError as exc:
                result = Result(new_id(), {"error": str(exc)}, name=upload.name)
            except (MemoryError, OSError):  # the server's memory or disk, not the file: no path in the message
                result = Result(new_id(), {"error": "the server ran out of memory or disk space on this file; "
                                                    "send it alone"}, name=upload.name)
            except Exception as exc:  # a failure of wbsa itself: the row says so, the batch goes on
                result = Result(new_id(), {"error": internal_error(exc)}, name=upload.name)
            store.add(result)
            batch.rows.append(row_of(result))
    finally:
        batch.done = True
