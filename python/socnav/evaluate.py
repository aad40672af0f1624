"""``python -m socnav.evaluate``: the paper's table for a policy (see :mod:`socnav.evaluation`;
``socnav.evaluate`` in Python is the function :func:`socnav.evaluation.evaluate`)."""

import sys

from socnav.evaluation import main

if __name__ == "__main__":
    sys.exit(main())
