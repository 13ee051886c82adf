"""The simulation scenarios patchgen ships (TOML data, installed as patchgen.sims)."""
