"""Terrain library (pure numpy): atomic terrains, tile composition, the terrain grid and its material map.

Importing the package registers every atomic terrain in ``registry.ATOMIC_TERRAINS``.
"""

from . import atomic, physical  # noqa: F401  (registration side effect)
