import sys

from wbsa.cli import main

sys.exit(main())
