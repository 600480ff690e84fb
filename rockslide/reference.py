"""Moved to `rockslide.core.reference`; this name is kept so that existing imports keep working."""

import sys

from .core import reference as _moved

sys.modules[__name__] = _moved
