"""Moved to `rockslide.core.physics`; this name is kept so that existing imports keep working."""

import sys

from .core import physics as _moved

sys.modules[__name__] = _moved
