"""``python -m mrexplore``: same as the ``mrexplore`` command."""

import sys

from mrexplore.cli import main

sys.exit(main())
