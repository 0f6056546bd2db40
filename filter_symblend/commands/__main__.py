"""``python -m filter_symblend.commands``: the ``symblend`` command."""

import sys

from .main import main

sys.exit(main())
