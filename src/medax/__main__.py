"""``python -m medax``: the ``medax`` command."""

import sys

from medax.cli.main import main

sys.exit(main())
