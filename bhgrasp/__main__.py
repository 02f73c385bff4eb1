"""``python -m bhgrasp`` runs the command line."""

import sys

from bhgrasp.cli import main

sys.exit(main())
