"""tunetrace-mpi: the merged database checked against its job list, parallel efficiency."""
