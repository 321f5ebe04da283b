"""``python -m cylfric``: the same command line as the ``cylfric`` script."""

from .cli import console_main

if __name__ == "__main__":
    console_main()
