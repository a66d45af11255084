"""``python -m app``: the same as the ``activecontour`` console script."""

import sys

from app.cli import console_script

sys.exit(console_script())
