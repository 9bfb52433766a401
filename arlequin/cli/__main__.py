"""``python -m arlequin.cli``: the ``arlequin`` command."""

import sys

from .main import main

sys.exit(main())
