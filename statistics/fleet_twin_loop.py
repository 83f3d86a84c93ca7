"""Moved to :mod:`wearcast.statistics.generators.fleet_twin_loop`; this name is an alias."""

import sys

from wearcast.statistics.generators import fleet_twin_loop as _moved

sys.modules[__name__] = _moved
