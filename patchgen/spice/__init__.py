"""The patch at the electrical level: a SPICE deck of the machine and bench, run in ngspice."""
