"""Local `mani` commands of the server distribution that run the science in-process: `mani hands`, `mani plan`."""
