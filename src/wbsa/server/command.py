"""``wbsa serve``: the clinic's page on this machine (127.0.0.1 and a free port unless told otherwise)."""

from __future__ import annotations

import argparse
import socket
import sys
import threading


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``serve`` subcommand."""
    from wbsa.cli_types import number_in

    p = sub.add_parser("serve", help="a local web page: drop a depth image, read the WBSA (and a batch table)",
                       description="Serve a web page on this machine that estimates WBSA from a depth image dropped "
                                   "on it (the same code as wbsa estimate), with the flags in plain words, the "
                                   "depth picture, the view, a 3-D view and downloads; several files give a table "
                                   "with a CSV. Prints the address to open; Ctrl-C stops it (docs/serve.md).")
    p.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default 127.0.0.1: this machine only; any other address, e.g. "
                        "0.0.0.0 for the network, requires a token, printed in the address to open)")
    p.add_argument("--token", default=None,
                   help="the token the page requires (default: a random one beyond 127.0.0.1, none on it; also "
                        "from WBSA_SERVE_TOKEN); at least 16 characters of A-Z a-z 0-9 - _ .")
    p.add_argument("--port", type=int, default=0, help="port (default 0: a free one, printed)")
    p.add_argument("--model", default=None, help="estimator model (.npz) or wbsa fit model (.json); default: the "
                                                 "default model")
    p.add_argument("--workers", type=number_in(1, 64, what="a number of threads"), default=2,
                   help="estimates run at once (default 2)")
    p.set_defaults(func=run_serve)


def bind(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host``:``port`` (0: a free port); a :class:`WbsaError` if it cannot be had."""
    from wbsa.errors import WbsaError

    if not 0 <= port <= 65535:
        raise WbsaError(f"port {port} must lie in 0-65535 (0: a free one)")
    try:
        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        sock = socket.socket(family, socket.SOCK_STREAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind((host, port))
        sock.listen(128)
    except OSError as exc:
        raise WbsaError(f"cannot listen on {host}:{port} ({exc.strerror or exc}); choose another --port, or "
                        "--port 0 for a free one") from None
    return sock


def url_of(sock: socket.socket) -> str:
    """The page's address for a bound socket."""
    host, port = sock.getsockname()[:2]
    shown = f"[{host}]" if ":" in host else host
    return f"http://{shown}:{port}/"


def start_in_thread(app, host: str = "127.0.0.1", port: int = 0):
    """Serve ``app`` from a background thread (tests, benchmarks); returns ``(url, stop)``.

    ``stop()`` asks the server to finish and waits for it (the app's temporary folder is removed).
    """
    import time

    import uvicorn

    sock = bind(host, port)
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning", lifespan="on", timeout_graceful_shutdown=5))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True, name="wbsa-serve")
    thread.start()
    deadline = time.monotonic() + 30
    while not server.started and thread.is_alive() and time.monotonic() < deadline:
        time.sleep(0.02)

    def stop() -> None:
        server.should_exit = True
        thread.join(timeout=15)
        sock.close()

    return url_of(sock), stop


def run_serve(args: argparse.Namespace) -> int:
    """Handler of ``wbsa serve``."""
    import os

    import uvicorn

    from wbsa.server.access import TOKEN_NAME, choose_token, needs_token
    from wbsa.server.addresses import page_urls
    from wbsa.server.app import create_app

    token = choose_token(args.host, args.token or os.environ.get("WBSA_SERVE_TOKEN"))
    app = create_app(args.model, workers=int(args.workers), token=token)
    sock = bind(args.host, args.port)
    urls = page_urls(args.host, sock.getsockname()[1], f"?{TOKEN_NAME}={token}" if token else "")
    also = f"; or {', '.join(urls[1:])}" if len(urls) > 1 else ""
    print(f"wbsa serve: open {urls[0]} in a browser (Ctrl-C stops){also}", flush=True)
    if needs_token(args.host):
        sys.stderr.write(f"note: listening on {args.host}: every request needs the token in the address above; "
                         "the traffic is not encrypted: put TLS in front beyond a trusted network (docs/serve.md)\n")
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning", lifespan="on"))
    server.run(sockets=[sock])
    return 0
