/* tunetrace-mpi: frame ranges of one sequence rendered by many ranks into one folder.
 * A range renders into OUT/.tunetrace-mpi/A-B/ (host --sequence A:B), then its frame files
 * are renamed into OUT (atomic, same filesystem) and its manifest kept as
 * OUT/.tunetrace-mpi/A-B.json; when every range of the sequence is done, rank 0 writes
 * OUT/manifest.json: the ranges' frames in order, as one host --sequence run writes it (the
 * history reset on the first frame only). OUT must be on a filesystem every rank sees. */
#ifndef TT_MPI_FRAMES_H
#define TT_MPI_FRAMES_H

#include "jobs.h"

/* Creates the range's empty work folder into dir. 0, or -1 (message in err). */
int tt_mpi_frames_prepare(const tt_mpi_job *job, char *dir, size_t dn, char *err, size_t n);

/* Moves the rendered range into the sequence's folder; *manifest = the range's manifest
 * text (malloc'ed). 0, or -1 (message in err). */
int tt_mpi_frames_finish(const tt_mpi_job *job, const char *dir, char **manifest, char *err,
                         size_t n);

/* Writes OUT/manifest.json of the sequence of jobs[first] from its ranges' manifests
 * (jobs[first..] that share its sequence). 0, or -1 (message in err). */
int tt_mpi_sequence_write(const tt_mpi_jobs *jobs, size_t first, char *err, size_t n);

#endif /* TT_MPI_FRAMES_H */
