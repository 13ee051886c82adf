"""What people read: the patch sheet, the wiring diagram, plots, pot tables and the file writer."""
