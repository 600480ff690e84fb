"""``python -m rockslide``: the command line, as the ``rockslide`` script."""

from .cli import main

if __name__ == "__main__":  # pragma: no branch
    main(prog_name="rockslide")
