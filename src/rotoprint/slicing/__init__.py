"""Fibre slicing: layers, device grids, fill rules."""

from .fibres import BACKENDS, FILL_RULES, Layer, SliceJob, slice_mesh
from .grid import Grid, make_grid
from .layers import LayerPlan, plan_layers
from .options import SliceOptions

__all__ = ["slice_mesh", "SliceOptions", "SliceJob", "Layer", "Grid", "make_grid", "LayerPlan", "plan_layers", "FILL_RULES", "BACKENDS"]
