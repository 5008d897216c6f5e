"""The web viewer (viser): terrains with their materials, tiles and spawn points; rollouts with force arrows.

``scene`` builds what is drawn as plain numpy data; ``rollout`` records, saves and loads rollouts and draws
the robot from its MJCF geoms; ``server`` pushes both to a viser web page with GUI controls.
"""
