"""Plots for notebooks and the CLI, on matplotlib without pyplot.

Every function draws into a given ``ax`` (or ``fig``) or a new ``matplotlib.figure.Figure``,
returns the figure and writes it only when given a path; no backend is selected here. The 3D
views (classified part, before/after, part mesh) share one opaque renderer,
[render_faces][medax.viz.view3d.render_faces].
"""
