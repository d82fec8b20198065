"""`python -m hapfluid run ...`: the launcher of the live stack."""
import sys

from .launcher import main

sys.exit(main())
