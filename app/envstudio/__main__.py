"""``python -m envstudio``."""

import sys

from envstudio.cli import main

sys.exit(main())
