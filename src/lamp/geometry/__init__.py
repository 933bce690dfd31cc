"""Planar geometry: SE(2) poses, shape footprints, collision and clearance queries."""
