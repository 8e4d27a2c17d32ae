"""`python -m polyfold`: the command line (`apps/cli/`)."""

from .apps.cli import main

if __name__ == "__main__":
    main()
