"""The ``skyquill`` command: one module ``cmd_<name>.py`` per subcommand, found automatically."""
