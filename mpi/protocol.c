/* tunetrace-mpi: the state every rank shares and the heartbeat (see protocol.h). */
#include "protocol.h"

#include <mpi.h>

volatile sig_atomic_t tt_mpi_stop;
volatile pid_t tt_mpi_running_child;
int tt_mpi_skip_finalize;

static const int64_t g_alive = 0; /* a heartbeat's body (buffer of requests freed at once) */

void tt_mpi_send_alive(int to) {
  MPI_Request q;
  MPI_Isend(&g_alive, 1, MPI_INT64_T, to, TAG_ALIVE, MPI_COMM_WORLD, &q);
  MPI_Request_free(&q);
}
