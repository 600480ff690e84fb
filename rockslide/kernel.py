"""Moved to `rockslide.core.kernel`; this name is kept so that existing imports keep working."""

import sys

from .core import kernel as _moved

sys.modules[__name__] = _moved
