"""The MAPush-style baseline's learned part: the mid-level pushing policy.

``lamp.rl.train`` trains it with PPO (stable-baselines3) on ``lamp/Push-v0`` over
randomised episodes on generated maps drawn apart from the benchmark scenes
(``lamp.rl.maps``), with the robots at the scenes' default speed; ``lamp.rl.policy``
stores and runs it (weights read with ``weights_only=True``). The planner ``mapush``
(``lamp.baselines.mapush``) drives it with subgoals along an obstacle-aware object path.
"""
