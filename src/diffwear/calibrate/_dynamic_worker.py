"""Entry point of the dynamic model's worker process (`reference`):
``python -m diffwear.calibrate._dynamic_worker READ_FD WRITE_FD``."""

import sys

from diffwear.calibrate.reference import _serve

if __name__ == "__main__":
    _serve(int(sys.argv[1]), int(sys.argv[2]))
