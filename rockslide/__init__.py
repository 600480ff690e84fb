"""rockslide: nonlinear seismic response of free-standing rectangular rigid blocks.

Rest, slip, liftoff (rocking with impacts), liftoff-slip interaction and overturning of a block on a
rigid foundation shaken horizontally and vertically, after Taniguchi (the paper in the README).
"""

__version__ = "0.1.0"
