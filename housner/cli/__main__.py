"""``python -m housner.cli``: the ``housner`` command."""

import sys

from housner.cli.app import main

sys.exit(main())
