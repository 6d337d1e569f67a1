"""``python -m quadcog.embedded`` (``make embedded``)."""
import sys

from .build import main

sys.exit(main())
