"""Moved to `rockslide.core.simulate`; this name is kept so that existing imports keep working."""

import sys

from .core import simulate as _moved

sys.modules[__name__] = _moved
