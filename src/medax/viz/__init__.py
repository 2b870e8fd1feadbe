"""Plots (matplotlib, Agg backend) and off-screen 3D views; imported lazily by the CLI."""
