"""``python -m rockslide``: the command line, as the ``rockslide`` script."""

from .cli import entry

if __name__ == "__main__":  # pragma: no branch
    entry()
