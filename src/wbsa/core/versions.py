"""Versions of the software whose numbers enter the results (recorded in study manifests and reports)."""

from __future__ import annotations

import platform

#: This package's version (also ``wbsa.__version__``).
WBSA_VERSION = "0.1.0"


def package_versions() -> dict[str, str]:
    """Versions of Python, wbsa and the libraries whose numbers enter the results.

    Returns
    -------
    dict
        ``{'python': '3.11.9', 'wbsa': '0.1.0', 'numpy': ..., 'open3d': ..., ...}``; packages that are not
        installed are left out.
    """
    from importlib.metadata import PackageNotFoundError, version

    out = {"python": platform.python_version(), "wbsa": WBSA_VERSION}
    for name in ("numpy", "pandas", "scipy", "statsmodels", "matplotlib", "open3d-cpu", "open3d", "anny", "torch",
                 "dask", "pyarrow"):
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            continue
    if "open3d-cpu" in out:
        out.setdefault("open3d", out.pop("open3d-cpu"))
    return out
