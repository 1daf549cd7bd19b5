"""Independent codes jaxdamp is checked and timed against: :mod:`jaxdamp.peers.lammps`."""
