"""Moved to :mod:`wearcast.statistics.generators.twin_effects`; this name is an alias."""

import sys

from wearcast.statistics.generators import twin_effects as _moved

sys.modules[__name__] = _moved
