"""Progress of one estimate as it runs: a stream of JSON lines for the page, the answer as its last line.

A request to ``POST /api/estimate`` or ``POST /api/result/{id}/pick`` that sends ``Accept:
application/x-ndjson`` gets, instead of one JSON answer, one JSON object per line (:data:`STREAM`):

- ``{"progress": {"stage": ..., "done": ..., "total": ...}}`` as the work goes on: ``reading`` the upload,
  ``subject`` (finding and measuring the person), ``regression``, ``body-fit`` (``done`` of ``total`` steps),
  ``answer`` (making the downloads); of a burst of one stage's steps only the latest is sent;
- ``{"status": 200 or 422 or 500, "answer": {...}}`` last: the answer a plain request gets, with the status it
  would have had.

A script that asks for JSON (any other ``Accept``) gets the one answer as before. The estimate runs to its end
and its answer is kept even if the page goes away half-way.
"""

from __future__ import annotations

import asyncio
import json

#: The media type of the progress stream: one JSON object per line.
STREAM = "application/x-ndjson"


def wants_stream(request) -> bool:
    """Whether ``request`` asks for the progress stream (its ``Accept`` names :data:`STREAM`)."""
    return STREAM in request.headers.get("accept", "")


def _line(obj: dict) -> bytes:
    from wbsa.strict_json import finite_or_none

    return (json.dumps(finite_or_none(obj), ensure_ascii=False, separators=(",", ":")) + "\n").encode()


async def stream_answer(runner, job, keep, failed, release):
    """The progress lines of ``job`` run in one of ``runner``'s threads, then its answer.

    Parameters
    ----------
    runner : wbsa.server.jobs.Runner
        Its place is already reserved (:meth:`~wbsa.server.jobs.Runner.slot`).
    job : callable
        ``job(progress)`` -> :class:`wbsa.server.jobs.Result`, run in a worker thread; ``progress(stage, done,
        total)`` may be called from that thread.
    keep : callable
        ``keep(result)``: keeps the result (for its downloads and picks), called when the job ends.
    failed : callable
        ``failed(exc)`` -> the one-line message of a failure of wbsa itself (no traceback).
    release : callable
        Gives the place back (:meth:`wbsa.server.jobs.Slot.hand_on`); called when the job ends (also if the
        page went away).

    Yields
    ------
    bytes
        One JSON object and a newline each.
    """
    loop = asyncio.get_running_loop()
    queue: asyncio.Queue = asyncio.Queue()

    def progress(stage: str, done: int, total: int) -> None:
        loop.call_soon_threadsafe(queue.put_nowait, {"stage": stage, "done": int(done), "total": int(total)})

    def ended(future) -> None:
        release()
        if not future.cancelled() and future.exception() is None:
            keep(future.result())
        queue.put_nowait(None)

    future = asyncio.ensure_future(runner.run(job, progress))
    future.add_done_callback(ended)
    finished = False
    while not finished:
        burst = [await queue.get()]
        while not queue.empty():
            burst.append(queue.get_nowait())
        if burst[-1] is None:
            finished = True
            burst.pop()
        for k, item in enumerate(burst):  # of a run of one stage's steps, only the latest is sent
            if k + 1 == len(burst) or burst[k + 1]["stage"] != item["stage"]:
                yield _line({"progress": item})
    try:
        result = future.result()
    except Exception as exc:  # a failure of wbsa itself: the answer says so, the server keeps running
        yield _line({"status": 500, "answer": {"error": failed(exc)}})
        return
    yield _line({"status": 422 if "error" in result.answer else 200, "answer": result.answer})
