"""The LUCIDAC: a netlist placed on its elements and lanes, and the configuration it loads."""
