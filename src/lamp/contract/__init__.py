"""The contract layer: what crosses layers, just above ``lamp.geometry``.

Every layer above imports these types downward; nothing here imports a layer above
``lamp.geometry``. One module per idea:

- ``plan``: the object-planner protocol (``ObjectPlanner``), ``Plan``/``PlanStatus`` and the
  closed loop's ``LoopPolicy``;
- ``transition``: the verified ``Transition`` a plan is made of;
- ``trajectory``: synchronised multi-robot trajectories (``MAX_STEP`` between rows);
- ``robots``: when two robot configurations count as the same;
- ``goals``: the scene format's success tolerances and pose errors;
- ``result``: ``ObjectResult`` and ``RunResult`` (result.json);
- ``model``: the manipulation model's motion range and robot budget;
- ``params``: parameters declared per planner (``ParamSpec``), parsed and validated;
- ``events``: what a run tells its observers (``SegmentEvent``, ``RunObserver``).
"""
