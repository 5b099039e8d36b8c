"""``python -m spacearm.cli``: the console script."""

import sys

from . import console_main

sys.exit(console_main())
