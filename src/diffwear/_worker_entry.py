"""Entry point of a worker process (`diffwear.worker`):
``python -m diffwear._worker_entry READ_FD WRITE_FD``."""

import sys

from diffwear.worker import serve

if __name__ == "__main__":
    serve(int(sys.argv[1]), int(sys.argv[2]))
