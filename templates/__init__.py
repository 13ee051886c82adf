"""The patch-sheet templates patchgen ships (jinja2 data, installed as patchgen.templates)."""
