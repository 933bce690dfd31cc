"""The fleet schedule: several objects moved at once by sub-teams (``schedule: concurrent``).

``coordinator.Fleet`` runs it; ``teams`` allocates robots, ``regions`` and ``segments`` say
what space a moving sub-team needs, ``turns`` runs the objects' closed loops as coroutines
and ``objects`` is one object's life. ``lamp.pipeline.schedule.run_concurrently`` is its
entry point.
"""
