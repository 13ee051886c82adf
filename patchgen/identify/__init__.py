"""From recordings of the standard bench tests to a bench profile and the plant's friction and length.

``recording`` and ``figures`` read and check what a user recorded; ``actuator``, ``friction``,
``pendulum`` and ``sensors`` fit each test; ``identify`` runs them all and ``profile`` writes the
bench profile and the plant table; ``report`` and ``plots`` say what was found and how well;
``benchtest`` generates recordings of every test from a spec's plant on a bench profile.
"""
