"""Machine and bench profiles: the analog computer and the real bench, as data."""
