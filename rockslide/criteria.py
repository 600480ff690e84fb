"""Moved to `rockslide.core.criteria`; this name is kept so that existing imports keep working."""

import sys

from .core import criteria as _moved

sys.modules[__name__] = _moved
