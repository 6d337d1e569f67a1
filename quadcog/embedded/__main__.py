"""``python -m quadcog.embedded`` (``make embedded``)."""
import sys

from quadcog.embedded.make_embedded import main

sys.exit(main())
