"""``python -m diffwear.cli``: the ``diffwear`` command."""

import sys

from .command import main

sys.exit(main())
