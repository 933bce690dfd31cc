"""The manipulation model: requested short object motion -> contact formations + push paths.

``load_model()`` returns the shipped, trained discrete-continuous flow-matching model
(GCo_DC-style, ``lamp.manip.network``); ``GeometricProposer`` gives proposals from the
hand-made data-generation strategies with the same API. Both return ``Proposal`` objects
in the object's frame (see ``lamp.manip.proposals``). PyTorch is imported only when the
learned model is loaded, so geometric-only users start fast.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from lamp.manip.contacts import CONTACT_GAP, CONTACT_OFFSET, HORIZON, MAX_ROBOTS, ROBOT_RADIUS
from lamp.manip.geometric import GeometricProposer
from lamp.manip.proposals import Proposal, ProposalModel

if TYPE_CHECKING:
    from lamp.manip.network import FlowProposer


def load_model(path: str | Path | None = None, threads: int | None = 1) -> FlowProposer:
    """Load a trained flow-matching proposer (default: the checkpoint shipped in the package).

    ``threads``: torch threads for this process (default 1, the fastest for the small
    sampling batches; None leaves torch's setting alone), see ``lamp.manip.network``.
    """
    from lamp.manip.network import load_model as _load

    return _load(path, threads=threads)


__all__ = [
    "CONTACT_GAP",
    "CONTACT_OFFSET",
    "HORIZON",
    "MAX_ROBOTS",
    "ROBOT_RADIUS",
    "GeometricProposer",
    "Proposal",
    "ProposalModel",
    "load_model",
]
