"""From a design to a patch: scaling, allocation, the netlist and the one reading of what it wires."""
