"""`python -m patchgen` runs the command line."""

from .cli import main

main()
