"""The request bodies ``service/cli.py`` still imports from here, re-exported from the
per-resource schema modules where they are defined (``route_schemas``, ``model_schemas`` ...).

Nothing else imports this module; it goes once ``service/cli.py`` imports the per-resource
modules directly.
"""

from wearcast.service.diagnosis_schemas import DiagnoseIn
from wearcast.service.model_schemas import ModelIn
from wearcast.service.prediction_schemas import PredictIn
from wearcast.service.reprofiling_schemas import ReprofilingIn
from wearcast.service.route_schemas import RouteIn
from wearcast.service.simulation_schemas import SimulationIn
from wearcast.service.wear_table_schemas import WearTableComputeIn

__all__ = ["DiagnoseIn", "ModelIn", "PredictIn", "ReprofilingIn", "RouteIn", "SimulationIn",
           "WearTableComputeIn"]
