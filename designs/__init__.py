"""The design specs patchgen ships (TOML data, installed as patchgen.designs)."""
