"""The optional dependencies: what only the analysis needs (matplotlib, pandas, dask, tqdm: the
`analysis` extra) or co-simulation (libcosimpy: the `cosim` extra). An FMU's runtime needs
none of them, so the library imports them only where they are used, through `require`, which
names the extra to install when one is missing."""
from __future__ import annotations

import importlib
from types import ModuleType

EXTRAS = {"matplotlib": "analysis", "pandas": "analysis", "dask": "analysis",
          "distributed": "analysis", "tqdm": "analysis", "libcosimpy": "cosim"}


class MissingDependency(ImportError):
    """An optional dependency is not installed; the message says which extra brings it."""


def require(module: str, needed_for: str) -> ModuleType:
    """The imported `module` (e.g. "pandas", "matplotlib.pyplot"), or MissingDependency
    "<needed_for> needs <package>, which is not installed: pip install <package> (or ...
    the <extra> extra)": the package is installed from its source, not an index.
    """
    package = module.split(".")[0]
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as error:
        if error.name is None or error.name.split(".")[0] != package:
            raise
        extra = EXTRAS.get(package, "all")
        raise MissingDependency(f"{needed_for} needs {package}, which is not installed: "
                                f"pip install {package} (or every dependency of the {extra!r} "
                                f"extra: pip install \".[{extra}]\" in herringbone's source "
                                "folder)") from None
