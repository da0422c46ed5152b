"""Foundations that know nothing of mechanisms: errors and exit codes (`errors`), plane vectors
(`vectors`), the table of deviation levels (`levels`), the solvers' settings (`settings`) and the
checks and atomic writes of the files a user names (`files`), a bounded memo of recent values
(`recent`)."""
