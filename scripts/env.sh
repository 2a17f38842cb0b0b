# Environment shared by scripts/test and scripts/bench (sourced, not executed).
# Parallel HDF5 of Debian's OpenMPI build, when present (hdf5-metno's build looks here).
if [ -z "${HDF5_DIR:-}" ] && [ -d /usr/lib/x86_64-linux-gnu/hdf5/openmpi ]; then
  export HDF5_DIR=/usr/lib/x86_64-linux-gnu/hdf5/openmpi
fi
# mpirun as root (CI containers) and more ranks than cores on small machines.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1
# Parallelism comes from MPI ranks; one BLAS thread per rank.
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
# No progress lines in logs (mpirun gives ranks a pseudo-terminal).
export SQUEAL_PROGRESS=${SQUEAL_PROGRESS:-0}
