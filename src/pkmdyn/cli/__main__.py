"""``python -m pkmdyn.cli``."""

import sys

from . import main

sys.exit(main())
