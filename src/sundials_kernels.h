/* sundials_kernels.h: compiled serial vector kernels for the SUNDIALS
 * backends (sundials_kernels.c).  Not part of the library's interface. */
#ifndef DRAPE_SUNDIALS_KERNELS_H
#define DRAPE_SUNDIALS_KERNELS_H

#include <nvector/nvector_serial.h>

/* Replace the hot operations of the NVECTOR_SERIAL vector v (and of every
 * vector later cloned from it) by compiled kernels with the same results,
 * and switch on the fused operations. */
void drape_sundials_install_kernels(N_Vector v);

#endif
