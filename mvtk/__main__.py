"""``python -m mvtk``: the ``mvtk`` command line (:mod:`mvtk.cli`)."""

import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main())
