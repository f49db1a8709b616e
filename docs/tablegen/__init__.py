"""docs/tables.py's library: the registry and one module per area of benchmarks."""
from . import preprocessing, runtime  # noqa: F401  (each registers its tables)
from .common import DOCS, ROOT, TABLES  # noqa: F401
