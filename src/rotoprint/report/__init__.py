"""Reports: plots and a self-contained HTML report of a build (no network: inline CSS and
JavaScript, images as data URIs)."""

from __future__ import annotations

from .html import render_report

__all__ = ["render_report"]
