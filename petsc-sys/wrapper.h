/* Everything squeal needs from PETSc and SLEPc; bindgen reads this file. */
#include <petsc.h>
#include <slepceps.h>
#include <slepcpep.h>
#include <slepcsvd.h>
/* MUMPS in single precision, called directly (la/single_lu.rs): PETSc hands MUMPS only its
   own scalar type. */
#include <smumps_c.h>
