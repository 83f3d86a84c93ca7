"""Moved to :mod:`wearcast.statistics.generators.fleet_twin_alt`; this name is an alias."""

import sys

from wearcast.statistics.generators import fleet_twin_alt as _moved

sys.modules[__name__] = _moved
