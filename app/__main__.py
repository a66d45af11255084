"""``python -m activecontour_app`` (``python -m app`` in the source tree): the ``activecontour``
console script."""

import sys

from .cli import console_script

sys.exit(console_script())
