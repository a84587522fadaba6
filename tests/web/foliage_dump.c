/* Prints foliage_place() (server/export/foliage.h) for the cases test_foliage.mjs
 * gives on its command line, so that it checks web/foliage.mjs against the C:
 *   foliage_dump px py pz|root qx qy qz k n size ...   (9 arguments per case, "root"
 *   in place of px, py and pz for a node without a parent)
 * One line per case: centre, along, across (9 numbers, %.17g) and the edge. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "foliage.h"

int main(int argc, char **argv) {
  for (int i = 1; i < argc;) {
    double p[3] = {0, 0, 0}, q[3];
    const double *parent = p;
    if (strcmp(argv[i], "root") == 0) {
      parent = NULL;
      i++;
    } else {
      if (i + 3 > argc) break;
      for (int a = 0; a < 3; a++) p[a] = strtod(argv[i++], NULL);
    }
    if (i + 6 > argc) {
      fprintf(stderr, "foliage_dump: a case needs q (3 numbers), k, n and size\n");
      return 2;
    }
    for (int a = 0; a < 3; a++) q[a] = strtod(argv[i++], NULL);
    int k = atoi(argv[i++]), n = atoi(argv[i++]);
    double size = strtod(argv[i++], NULL);
    foliage_leaf f;
    foliage_place(parent, q, k, n, size, &f);
    for (int a = 0; a < 3; a++) printf("%.17g ", f.centre[a]);
    for (int a = 0; a < 3; a++) printf("%.17g ", f.along[a]);
    for (int a = 0; a < 3; a++) printf("%.17g ", f.across[a]);
    printf("%.17g\n", f.edge);
  }
  return 0;
}
