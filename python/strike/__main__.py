# SPDX-License-Identifier: MIT
"""python3 -m strike batch ...: the package's commands (so far: batch)."""
import sys

from . import batch

if __name__ == "__main__":
    if len(sys.argv) < 2 or sys.argv[1] != "batch":
        sys.stderr.write("usage: python3 -m strike batch MANIFEST.jsonl -o DIR [options] (see --help)\n")
        sys.exit(1)
    sys.exit(batch.main(sys.argv[2:]))
