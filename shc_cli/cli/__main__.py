"""``python -m shc_cli.cli``: the ``shc`` command."""

from shc_cli.cli import main

main()
