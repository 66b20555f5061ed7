"""Seeing the robot: `shc view` (a browser page served by viser) and `shc render` (headless video).

Nothing here is imported by `shc --help`: the commands import it when they run.
"""
