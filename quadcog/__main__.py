import sys

from quadcog.cli import main

sys.exit(main())
