"""Optional dependencies: the one way mien imports a module that an extra (``pip install 'mien[extra]'``) brings.

:func:`require` imports a module or raises :class:`~mien.errors.MissingExtraError` naming the extra that
installs it; :func:`available` asks without raising (for a fast path with a numpy fallback). The library, the
CLI (which turns the error into exit code 2 and its message) and the server (which counts it as a rejection)
all see the same error. Which extra brings which module is the table :data:`EXTRA_OF`, in one place.

>>> require("json", "core").__name__
'json'
>>> available("a_module_that_is_not_there")
False
>>> try:
...     require("a_module_that_is_not_there", "render")
... except ImportError as error:
...     print(error)
a_module_that_is_not_there is needed for this; install it with: pip install 'mien[render]'
"""

from __future__ import annotations

import importlib
import types
from functools import cache

from mien.errors import MissingExtraError

__all__ = ["EXTRA_OF", "available", "require"]

EXTRA_OF: dict[str, str] = {
    "numba": "fast",
    "matplotlib": "plot",
    "tqdm": "plot",
    "moderngl": "render",
    "imageio_ffmpeg": "render",
    "PIL": "render",
    "mediapipe": "track",
    "av": "track",
    "kmedoids": "laughter",
    "scipy": "au",
    "dask": "distributed",
    "distributed": "distributed",
    "ai_edge_litert": "validate",
    "meshopt": "heads",
    "DracoPy": "heads",
    "fastapi": "serve",
    "uvicorn": "serve",
    "orjson": "serve",
    "websockets": "serve",
    "sqlalchemy": "study",
    "psycopg": "study",
    "pandas": "study",
    "pingouin": "study",
    "statsmodels": "study",
}
"""Top-level module -> the extra of ``pyproject.toml`` named when it is missing: one that installs it, the
smallest where several do, except ``PIL``, named for rendering (``heads`` installs it too, for textures)."""


def require(module: str, extra: str | None = None) -> types.ModuleType:
    """Import ``module`` (dotted names too), or raise :class:`MissingExtraError` naming ``extra``.

    ``extra`` defaults to :data:`EXTRA_OF` of the top-level package (``"all"`` when the table lacks it).
    """
    try:
        return importlib.import_module(module)
    except ImportError as error:
        top = module.split(".", 1)[0]
        missing = (error.name or top).split(".", 1)[0]
        if missing not in (top, module):  # the module is there but one of its own imports failed: say that one
            raise MissingExtraError(missing, extra or EXTRA_OF.get(missing, EXTRA_OF.get(top, "all"))) from error
        raise MissingExtraError(top, extra or EXTRA_OF.get(top, "all")) from None


@cache
def available(module: str) -> bool:
    """True when ``module`` imports (cached: the answer does not change within a process)."""
    try:
        importlib.import_module(module)
    except ImportError:
        return False
    return True
