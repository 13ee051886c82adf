"""One function per command, between the command line and the domain layers: the inputs resolved
once, a run plan, and a report holding every figure and verdict the command prints and writes."""
