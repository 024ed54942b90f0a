"""``python -m tmpnav`` is the same as the ``tmpnav`` command."""

from tmpnav.cli import main

if __name__ == "__main__":
    main()
