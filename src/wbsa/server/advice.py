"""The page's rows for an estimate's flags: the meaning and what to do come from
:data:`wbsa.estimation.flags.FLAG_RECORDS` (one record per flag: its meaning and its page advice), the detail
from the estimate, in the page's words (:func:`wbsa.errors.page_text`)."""

from __future__ import annotations


def flag_rows(flags: dict[str, str]) -> list[dict[str, str]]:
    """The page's rows for an estimate's ``flags``: name, meaning, the estimate's detail (in the page's words),
    what to do (the record's page advice).

    >>> flag_rows({"cut_off": "subject pixels on the image border"})[0]["meaning"]
    'the subject touches the image border and may be cut off'
    """
    from wbsa.errors import page_text
    from wbsa.estimation.flags import DEFAULT_ADVICE, FLAG_RECORDS

    rows = []
    for name, detail in flags.items():
        record = FLAG_RECORDS.get(name)
        rows.append({"name": name, "meaning": page_text(record.meaning) if record else name.replace("_", " "),
                     "detail": page_text(detail), "todo": record.advice if record else DEFAULT_ADVICE})
    return rows
