"""`mani` subcommands backed by the science package (heavy imports happen inside the commands)."""
