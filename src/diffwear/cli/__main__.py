"""``python -m diffwear.cli``: the ``diffwear`` command."""

from .command import entry

entry()
