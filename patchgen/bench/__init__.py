"""The patched circuit on the bench: circuit arrays, the compiled engine, Monte-Carlo runs, diagnosis."""
