"""Pump-up from hanging (thesis chapter 3), the hand-off zone and the whole manoeuvre."""
