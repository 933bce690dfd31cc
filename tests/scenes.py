"""Scene dicts several test modules share (not a test module: nothing here is collected)."""

from __future__ import annotations

#: Three robots of the shipped radius beside one box, an open 2.2 x 2 m room: planned and
#: executed in a second or two, by any planner.
TINY = {
    "format": "lamp-scene/1", "name": "tiny", "workspace": [2.2, 2.0],
    "robots": {"radius": 0.05, "starts": [[0.2, 0.3], [0.2, 0.6], [0.2, 0.9]]},
    "obstacles": [],
    "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [0.85, 1.0, 0.0],
                 "goal": [1.25, 1.0, 0.0]}],
}
