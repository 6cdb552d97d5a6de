"""Sub-command groups of the ``anklelab`` command, one module per group."""
