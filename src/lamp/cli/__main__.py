"""``python -m lamp.cli``: the ``lamp`` command."""

from lamp.cli import app

app()
