"""``python -m services`` (``python -m livedrummer._services`` from a wheel) is ``livedrummer``."""

import sys

from .cli import main

sys.exit(main())
