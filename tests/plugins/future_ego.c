/*
 * A controller plugin that declares an ABI version newer than this vsd-sumo speaks, for the
 * test that such a library is refused with the versions it could have declared.
 */
#include <stddef.h>

#include "vsd/sim/controller_abi.h"

static int future_step(vsd_controller* self, const vsd_observation* observation, double dt, vsd_command* command) {
  (void)self;
  (void)observation;
  (void)dt;
  command->accel = 0.0;
  command->curvature = 0.0;
  return 0;
}

static vsd_controller* future_create(const char* const* names, const double* values, int count, char* error,
                                     int error_size) {
  (void)names;
  (void)values;
  (void)count;
  (void)error;
  (void)error_size;
  return NULL;
}

static const vsd_controller_api kFutureEgo = {
    VSD_CONTROLLER_ABI_VERSION + 1, "future_ego", "declares an ABI version from the future", future_create, NULL,
    future_step, NULL,
};

__attribute__((visibility("default"))) const vsd_controller_api* vsd_controller_entry(int index) {
  return index == 0 ? &kFutureEgo : NULL;
}
