/* sylva: species parameters (docs/model.md symbols; scenario.md keys and defaults). */
#ifndef SYLVA_PARAMS_H
#define SYLVA_PARAMS_H

#include "equations.h"

/** How a species turns light into growth. */
typedef enum sylva_allocation {
  SYLVA_ALLOC_LGTM = 0, /**< Borchert-Honda + priority (LGTM eq. 1-2) */
  SYLVA_ALLOC_NONE = 1  /**< simplified IGM: the growth equation alone */
} sylva_allocation;

/** Every parameter of one species. Angles in degrees, lengths in metres. */
typedef struct sylva_species_def {
  double rho;              /**< internode length */
  sylva_equation growth;   /**< growth equation X(t), internodes */
  sylva_allocation allocation;
  double sprout_light;     /**< simplified IGM: least bud light that sprouts */
  double lambda;           /**< BH main/lateral weight */
  double k;                /**< ratio of top-priority nodes */
  double w1, w2, w3;       /**< priority weights */
  int tau;                 /**< iterations of apical control */
  double alpha;            /**< light conversion rate */
  int leaf_age;            /**< iterations a node bears leaves: it collects light and its
                                lateral bud may sprout only while age <= leaf_age */
  double node_cost;        /**< resource units one new internode costs */
  int apical_zone;         /**< internodes below an axis's apex whose lateral buds stay
                                dormant (LGTM; docs/model.md, "Allocation") */
  double apical_flow;      /**< share of the BH main flow the trunk's apex takes on top of
                                its own light (docs/model.md, "Allocation") */
  double sigma;            /**< light sensitivity */
  double mu;               /**< weight of the optimal direction */
  double gamma;            /**< weight of the tropism */
  double tropism[3];       /**< tropism vector */
  double theta;            /**< branching angle */
  double divergence;       /**< phyllotaxis divergence angle */
  double b_min, b_max;     /**< shade impact base */
  int pyramid_depth;       /**< Qd, voxels */
  double shade_spread;     /**< pyramid half-width per voxel of depth */
  double shade_column;     /**< shade per voxel of the column below the pyramid */
  double r_s;              /**< shedding threshold */
  double r_tip;            /**< terminal radius, m */
  double pipe_exponent;    /**< v of the pipe model */
  int m0, m_min;           /**< marker points m(T) = max(m_min, m0 - T) */
  double cone_angle;       /**< marker cone half-angle */
  double cone_radius;      /**< marker cone length, internodes */
  int initial_nodes;       /**< internodes of the initial vertical trunk */
  /* Real species (docs/model.md, "Species in years"). All zero for the IGM presets,
   * which then grow exactly as before these fields existed. */
  double ref_rho;          /**< > 0: the counts above (growth equation, initial_nodes,
                                apical_zone, cone_radius, pyramid_depth) are given for
                                internodes of this length, m, and scale with ref_rho / rho
                                so that they act as lengths; lateral buds stand at most
                                one per ref_rho of axis; 0: counts are taken as given */
  double acclimation;      /**< 0..1: a branch is shed when its light is below r_s times
                                the stem's mean light to this power (0: r_s alone) */
  double shade_weight;     /**< factor on every node's shade (pyramid and column) */
  double lift;             /**< 0..0.9: after each iteration, the trunk's branches below
                                this share of the height are cut, as street trees are
                                lifted (docs/model.md, "Species in years") */
  double crown_max;        /**< >= 0: no node stands farther from its stem's root, across,
                                than half of crown_max * H^crown_max_exp m for the stem's
                                height H (0: no limit; docs/model.md, "Species in years") */
  double crown_max_exp;    /**< 0..2: the exponent of that limit */
  /* Foliage (docs/model.md, "Foliage"): what every leaf-bearing node carries. It
   * changes no growth. */
  double leaf_size;        /**< m: a leaf's length, the edge of its square card */
  int leaf_density;        /**< leaves per leaf-bearing node */
  int leaf_colour;         /**< 0xRRGGBB, the scenario's "#rrggbb" */
  double heartwood;        /**< 0..1: each season a node's pipes (r^v) grow by this share
                                of its functional pipes, the tips' above it: pipes whose
                                leaves are gone stay in the wood (docs/model.md, "Species
                                in years"); 0: the pipe model alone */
  double lateral_reach;    /**< 1..4: a shoot off the trunk may grow up to this many times
                                the leader's path a season, graded from 1 at the stem's top
                                to this a crown height below it (LGTM allocation;
                                docs/model.md, "Species in years"); 1: the leader's cap */
  /* Wood and carbon (docs/model.md, "Wood and carbon"). They change no growth. */
  double wood_density;     /**< kg/m^3 dry weight per fresh volume; 0: none (no
                                biomass_model, and no volume allometry) */
  int biomass_form;        /**< the above-ground biomass allometry, D the dbh in cm and H
                                the height in m: 0 none; 1 volume (m^3) a D^b H^c, times
                                wood_density; 2 dry weight (kg) a D^b H^c; 3 dry weight
                                a D^b H^c - exp(p + q / D), less the foliage */
  double biomass_a, biomass_b, biomass_c, biomass_p; /**< its coefficients */
  double biomass_q;
  double biomass_factor;   /**< (0, 1]: times the allometry (0.8 for a rural equation on
                                an open-grown tree) */
  /* Stands (docs/model.md, "Stands"): trees that differ and trees that die. All zero
   * (mortality_years and snag_years aside) for species that grow as before. */
  double stock_spread;     /**< 0..1: the spread of planted stock, as the coefficient of
                                variation of its height (nursery) */
  double vigour_spread;    /**< 0..2: the standard deviation of the log of a plant's
                                vigour, its growth time per season */
  double height_light;     /**< >= 0: K of the leader's light response l (1 + K) / (l + K)
                                (0: height growth does not answer light) */
  double mortality_light;  /**< 0..1: a stem whose leaves' mean relative light stays below
                                this for mortality_years seasons dies (0: never) */
  int mortality_years;     /**< seasons of low light before a stem dies */
  double mortality;        /**< 0..1: background probability of death per season */
  int snag_years;          /**< seasons a dead stem stands as a snag before it falls */
  int years;               /**< 1: one iteration is one growing season; stems report ages */
  int nursery;             /**< years a plant of age 0 has grown in the nursery, in open
                                light, before it is planted (years species only) */
} sylva_species_def;

/** The share of a leaf's square card its blade covers: an ellipse inscribed in the
 *  card, pi / 4. A leaf's area is SYLVA_LEAF_FILL * leaf_size^2. */
#define SYLVA_LEAF_FILL 0.78539816339744831

/** The defaults of scenario.md (the igm-fig11 row with r_s 0.35). */
sylva_species_def sylva_default_species_def(void);

/** Checks ranges; on failure returns SYLVA_ERANGE and names the field in *field. */
int sylva_species_check(const sylva_species_def *def, const char **field);

#endif
