"""The command line's exit statuses (a module of its own: the console script's entry point
reads them before it imports anything else, see :func:`graphvision.cli.main.entry`)."""

EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_INTERRUPTED, EXIT_TERMINATED = 0, 1, 2, 130, 143
EXIT_HUNG_UP = 129  # SIGHUP: 128 + its number, as a shell reports a command it ended
