/* Phase 4: appending shoots: default direction with phyllotaxis and branching angle,
 * marker points with space-colonisation competition, tropism. */
#ifndef SYLVA_SHOOT_H
#define SYLVA_SHOOT_H

/** Direction of a lateral bud: d (unit, the parent axis) turned by theta degrees
 *  around an axis perpendicular to d, itself turned by phi degrees around d. */
void sylva__lateral_direction(const double d[3], double theta, double phi, double out[3]);
#endif
