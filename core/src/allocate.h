/* Phases 2-3: resource allocation (Borchert-Honda + priority) and the growth cap. */
#ifndef SYLVA_ALLOCATE_H
#define SYLVA_ALLOCATE_H

/** BH share of a node: (Lm + Ll)(1 - lambda) Ll / (lambda Lm + (1 - lambda) Ll), 0 when
 *  the denominator is 0. */
double sylva__bh_share(double lm, double ll, double lambda);
/** Priority weight of rank (0 = best) among n nodes: w1 for rank/n < k, then linear
 *  from w2 down to w3 over [k, 1). */
double sylva__priority_weight(int rank, int n, double k, double w1, double w2, double w3);
#endif
