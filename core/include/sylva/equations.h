/* sylva: growth equations X(t) in node units and their analytic derivatives. */
#ifndef SYLVA_EQUATIONS_H
#define SYLVA_EQUATIONS_H

#include <stdbool.h>

/** Kinds of growth equation (docs/model.md, "Cap"). */
typedef enum sylva_equation_kind {
  SYLVA_EQ_LOGISTIC = 0,    /**< p = {X0, Xm, r} */
  SYLVA_EQ_BERTALANFFY = 1, /**< p = {beta1, beta2} */
  SYLVA_EQ_WEIBULL = 2,     /**< p = {omega1, omega2, omega3} */
  SYLVA_EQ_GOMPERTZ = 3,    /**< p = {A, B, C}: X = A exp(-B exp(-C t)) */
  SYLVA_EQ_COUNT
} sylva_equation_kind;

/** A growth equation: its kind and up to three parameters. */
typedef struct sylva_equation {
  sylva_equation_kind kind;
  double p[3];
} sylva_equation;

/** X(t): path length from root to tip, internodes. */
double sylva_equation_value(const sylva_equation *eq, double t);
/** dX/dt(t), analytic. */
double sylva_equation_rate(const sylva_equation *eq, double t);
/** The limit of X as t grows (Xm, beta1, omega1, A). */
double sylva_equation_limit(const sylva_equation *eq);
/** c(T) = round half up of dX/dt(T - 1), never below 0. */
int sylva_equation_cap(const sylva_equation *eq, int iteration);
/** The cap of f times the equation: round half up of f dX/dt(T - 1), never below 0. */
int sylva_equation_cap_scaled(const sylva_equation *eq, int iteration, double f);
/** True when dX/dt is decreasing at t = T - 1 (past the inflection point). */
bool sylva_equation_decreasing(const sylva_equation *eq, int iteration);
/** The stopping rule: cap 0 while the rate is already decreasing. */
bool sylva_equation_stops(const sylva_equation *eq, int iteration);
/** Name of an equation kind ("logistic"), or NULL. */
const char *sylva_equation_name(sylva_equation_kind kind);

#endif
