/* heliodon — minimum-cost transportation problem (private to the library).
 * Used for the lobe transport plans of measured-BSDF interpolants
 * (bsdf_rbf_fit.c); docs/design/measured.md. */
#ifndef HELIODON_TRANSPORT_H
#define HELIODON_TRANSPORT_H

#include "heliodon/common.h"

/* Move supplies a[0..na-1] onto demands b[0..nb-1] (non-negative; the
 * demands are rescaled to the supplies' total) at the least total cost
 * sum flow[i*nb+j] * c[i*nb+j].  flow (na*nb) is overwritten; at most
 * na+nb-1 entries are non-zero.  Solved exactly by the network simplex
 * method on the bipartite graph (a spanning tree of na+nb-1 basic arcs,
 * potentials u_i + v_j = c_ij on them, entering arcs by block pricing,
 * leaving arcs by the strongly-feasible rule), started from the greedy
 * least-cost solution.  Optimal when no arc has a reduced cost below
 * -1e-10 x the largest cost.  u (na) and v (nb), when not NULL, receive
 * the final potentials (a certificate: c_ij - u_i - v_j >= -tol for all
 * arcs, = 0 where flow > 0); *npivots (may be NULL) the pivot count.
 * Returns HD_ERR_NOMEM, HD_ERR_RANGE if the pivot limit (a safeguard
 * against cycling) was hit (flow then holds the feasible plan reached),
 * else HD_OK. */
hd_status hd_transport_solve(int na, int nb, const double *a, const double *b, const double *c,
                             double *flow, double *u, double *v, long *npivots);

/* The plan Radiance 6.1's pabopto2bsdf makes for the same problem: a
 * transportation simplex started from Russell's approximation, pivoting
 * on the cell of most negative reduced cost (first in row-major order on
 * ties), stopped when none is below -1e-6 x the largest cost or when the
 * objective rises; like Radiance's output, the basic cell held in the last
 * of its na+nb slots is left out of flow unless that slot is free.  Not
 * optimal in general (docs/design/measured.md); the trees made from it
 * agree with Radiance's.  Supplies and demands that differ by more than
 * 1e-6 relative are balanced by a dummy row or column at no cost.
 * Returns HD_ERR_RANGE for negative input or when a pivot limit far above
 * anything seen was hit (flow then holds the plan reached). */
hd_status hd_transport_radiance(int na, int nb, const double *a, const double *b, const double *c,
                                double *flow, long *npivots);

#endif
