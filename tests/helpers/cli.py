"""Run the ``wbsa`` command in-process and check its one-line errors."""

from __future__ import annotations

import contextlib
import io

from wbsa.cli import main


def run_cli(*args) -> tuple[int, str, str]:
    """``wbsa ARGS`` in this process: (exit status, stdout, stderr)."""
    o, e = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(o), contextlib.redirect_stderr(e):
        code = main([str(a) for a in args])
    return code, o.getvalue(), e.getvalue()


def assert_one_line_error(code: int, err: str, *fragments: str) -> None:
    """Exit 2 with one ``error:`` line holding every fragment, no traceback."""
    assert code == 2 and err.startswith("error: ") and err.count("\n") == 1 and "Traceback" not in err, err
    for f in fragments:
        assert f in err, err
