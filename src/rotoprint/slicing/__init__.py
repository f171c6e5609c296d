"""Fibre slicing: layers, device grids, fill rules."""

from .fibres import BACKENDS, FILL_RULES, Layer, SliceJob, slice_mesh
from .grid import Grid, make_grid
from .layers import LayerPlan, plan_layers

__all__ = ["slice_mesh", "SliceJob", "Layer", "Grid", "make_grid", "LayerPlan", "plan_layers", "FILL_RULES", "BACKENDS"]
