"""``python -m crowdbench.cli``."""

import sys

from crowdbench.cli import main

sys.exit(main())
