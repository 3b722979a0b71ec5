"""The entry point PyInstaller freezes into rac-console.exe: the CLI's own ``main``."""

import sys

from rac_console.cli.main import main

if __name__ == "__main__":
    sys.exit(main())
