/* Everything squeal needs from PETSc and SLEPc; bindgen reads this file. */
#include <petsc.h>
#include <slepceps.h>
#include <slepcpep.h>
#include <slepcsvd.h>
