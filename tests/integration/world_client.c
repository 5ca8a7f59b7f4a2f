/* A user's C program against the installed world library, built with pkg-config only
 * (InstallPackage.AUsersCProgramMeasuresThePlant): it opens a scenario file's world, reads the
 * truth and a measurement, and checks z - v = H x for the scalar position sensor 0 of the
 * default scenario (H = [1 0 0 0]). Exit 0 when all holds, 1 with a message otherwise. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <sensornet/world.h>

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  FILE* f = fopen(argv[1], "rb");
  if (f == NULL) return 2;
  static char text[1 << 16];
  const size_t n = fread(text, 1, sizeof text - 1, f);
  fclose(f);
  text[n] = '\0';
  char why[256];
  sn_world* w = sn_world_open(text, 7, why, sizeof why);
  if (w == NULL) {
    fprintf(stderr, "world_client: %s\n", why);
    return 1;
  }
  double x[16], z[4], v[4];
  if (sn_world_abi_version() != SN_WORLD_ABI_VERSION || sn_world_states(w) != 4 ||
      sn_world_state(w, 2, 1.5, x) != 0 || sn_world_noise(w, 2, 0, 5, v) != 0 ||
      sn_world_measure(w, 2, 0, 5, 1.5, z) != 0 || fabs(z[0] - v[0] - x[0]) > 1e-12) {
    fprintf(stderr, "world_client: %s\n", sn_world_error(w));
    return 1;
  }
  printf("world_client: x(1.5) = [%g, %g, %g, %g], z = %g\n", x[0], x[1], x[2], x[3], z[0]);
  sn_world_close(w);
  return 0;
}
