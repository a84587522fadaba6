/* Growth equations X(t) (IGM section 4.3) with analytic first derivatives. */
#include "sylva/equations.h"

#include <math.h>

double sylva_equation_value(const sylva_equation *eq, double t) {
  const double *p = eq->p;
  switch (eq->kind) {
  case SYLVA_EQ_LOGISTIC: return p[1] / (1.0 + (p[1] / p[0] - 1.0) * exp(-p[2] * t));
  case SYLVA_EQ_BERTALANFFY: {
    double u = 1.0 - exp(-p[1] * t);
    return p[0] * u * u * u;
  }
  case SYLVA_EQ_WEIBULL: return p[0] * (1.0 - exp(-p[1] * pow(t, p[2])));
  case SYLVA_EQ_GOMPERTZ: return p[0] * exp(-p[1] * exp(-p[2] * t));
  default: return 0.0;
  }
}

double sylva_equation_rate(const sylva_equation *eq, double t) {
  const double *p = eq->p;
  switch (eq->kind) {
  case SYLVA_EQ_LOGISTIC: {
    double a = p[1] / p[0] - 1.0, e = exp(-p[2] * t), d = 1.0 + a * e;
    return p[1] * p[2] * a * e / (d * d);
  }
  case SYLVA_EQ_BERTALANFFY: {
    double e = exp(-p[1] * t), u = 1.0 - e;
    return 3.0 * p[0] * p[1] * e * u * u;
  }
  case SYLVA_EQ_WEIBULL: {
    if (t <= 0.0) return p[2] < 1.0 ? INFINITY : (p[2] == 1.0 ? p[0] * p[1] : 0.0);
    double tp = pow(t, p[2]);
    return p[0] * p[1] * p[2] * (tp / t) * exp(-p[1] * tp);
  }
  case SYLVA_EQ_GOMPERTZ: {
    double e = exp(-p[2] * t);
    return p[0] * p[1] * p[2] * e * exp(-p[1] * e);
  }
  default: return 0.0;
  }
}

double sylva_equation_limit(const sylva_equation *eq) {
  return eq->kind == SYLVA_EQ_LOGISTIC ? eq->p[1] : eq->p[0];
}

int sylva_equation_cap(const sylva_equation *eq, int iteration) {
  return sylva_equation_cap_scaled(eq, iteration, 1.0);
}

int sylva_equation_cap_scaled(const sylva_equation *eq, int iteration, double f) {
  double r = f * sylva_equation_rate(eq, (double)(iteration - 1));
  if (!(r > 0.0)) return 0;
  if (r > 1e6) return 1000000;
  return (int)floor(r + 0.5);
}

bool sylva_equation_decreasing(const sylva_equation *eq, int iteration) {
  /* Compared at consecutive integer times so that the rule needs no second
   * derivative and an equation whose rate starts at 0 is never "decreasing" at
   * its start. */
  if (iteration < 2) return false;
  return sylva_equation_rate(eq, (double)(iteration - 1)) <
         sylva_equation_rate(eq, (double)(iteration - 2));
}

bool sylva_equation_stops(const sylva_equation *eq, int iteration) {
  /* Less than one whole internode per iteration once past the inflection
   * (docs/model.md, "Stop"). */
  return !(sylva_equation_rate(eq, (double)(iteration - 1)) >= 1.0) &&
         sylva_equation_decreasing(eq, iteration);
}

const char *sylva_equation_name(sylva_equation_kind kind) {
  static const char *const names[SYLVA_EQ_COUNT] = {"logistic", "bertalanffy", "weibull",
                                                    "gompertz"};
  return (unsigned)kind < SYLVA_EQ_COUNT ? names[kind] : 0;
}
