"""``python -m alpes_dyn.cli``: the ``alpes-dyn`` command."""

import sys

from . import main

sys.exit(main())
