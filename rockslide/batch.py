"""Moved to `rockslide.core.batch`; this name is kept so that existing imports keep working."""

import sys

from .core import batch as _moved

sys.modules[__name__] = _moved
