import sys

from service.workers.process import main

sys.exit(main())
