"""The `mani` command line: one entry point, subcommands registered as plugins."""
