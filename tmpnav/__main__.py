"""``python -m tmpnav`` is the same as the ``tmpnav`` command (whose entry point is :func:`main`)."""

import sys


def main() -> None:
    """The command line, loaded here so that a Ctrl-C while it loads is one line too."""
    try:
        from tmpnav.cli import main as run
    except KeyboardInterrupt:
        sys.stderr.write("error: interrupted\n")
        sys.exit(130)
    run()


if __name__ == "__main__":
    main()
