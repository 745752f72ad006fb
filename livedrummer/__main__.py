"""``python -m livedrummer`` is the ``livedrummer`` command."""

import sys

from livedrummer.cli import main

sys.exit(main())
