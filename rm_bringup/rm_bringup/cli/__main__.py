"""``python -m rm_bringup.cli`` runs rmcli."""

import sys

from .main import main

sys.exit(main())
