"""`python3 -m phymul sweep SWEEP.yaml -o DIR ...`: what `phymul sweep` runs."""
import sys

from .sweep import main

if __name__ == "__main__":
    if sys.argv[1:2] != ["sweep"]:
        print("usage: python3 -m phymul sweep SWEEP.yaml -o DIR [--scheduler tcp://HOST:PORT] "
              "[--workers N] [--resume]", file=sys.stderr)
        sys.exit(1)
    sys.exit(main(sys.argv[2:]))
