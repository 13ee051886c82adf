"""Studies over many patches: recommend a patch, sweep the plant's parameters."""
