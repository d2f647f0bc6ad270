"""``python -m wipelab`` is the same as the ``wipelab`` command."""

from wipelab.cli import main

main()
