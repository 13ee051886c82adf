"""What a user gives patchgen: spec, scenario, the files they come in, and the one-line error for bad input."""
