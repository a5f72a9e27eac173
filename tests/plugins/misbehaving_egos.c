/*
 * Ego controller plugins that misbehave on purpose, for the robustness tests
 * (built for the tests only: build/plugins/libvsd_misbehaving_egos.so, target
 * vsd_misbehaving_egos). Until their fault strikes they drive sensibly (hold
 * the speed, follow a leader at a 2 s gap, pure pursuit on the lane preview),
 * so that a scenario without the fault completes normally.
 *
 *   name            fault
 *   crashing_ego    dereferences a null pointer (SIGSEGV)
 *   aborting_ego    abort() (SIGABRT, like a failed assertion)
 *   exiting_ego     exit(0): ends the process "successfully"
 *   hanging_ego     loops forever (busy), never returns
 *   failing_ego     step() returns an error status (an ordinary, reported failure)
 *   misbehaving_ego the fault chosen per scenario by the parameter `kind`:
 *                   0 none, 1 crash, 2 abort, 3 exit(0), 4 hang, 5 error status
 *
 * Parameters (numbers, or expressions over the scenario's inputs):
 *   fault   != 0: this concrete scenario gets the fault (default 1). E.g.
 *           `fault: v_ego > 12` faults only the scenarios with a fast Ego.
 *   at      s: the first step at or after this time faults (default 0);
 *           < 0: create() faults instead (before the first step).
 *   kind    misbehaving_ego only (see above; an expression over the inputs lets
 *           one run hold every kind of fault, e.g. `kind: (v_ego > 12) + (v_ego > 14)`).
 *
 * Example (scenario YAML):
 *   controller: {name: crashing_ego, library: ../build/plugins/libvsd_misbehaving_egos.so,
 *                params: {fault: v_ego > 12, at: 1.0}}
 * or for a closed-loop export:
 *   --closed-loop --controller hanging_ego --controller-library build/plugins/libvsd_misbehaving_egos.so
 *   --controller-param at=3 --step-timeout 0.5
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "vsd/sim/controller_abi.h"

enum fault_kind { FAULT_NONE, FAULT_CRASH, FAULT_ABORT, FAULT_EXIT, FAULT_HANG, FAULT_FAIL, FAULT_CHOSEN };

struct vsd_controller {
  enum fault_kind kind;
  int armed;  /* this scenario gets the fault */
  double at;  /* s */
};

static void strike(enum fault_kind kind) {
  switch (kind) {
    case FAULT_CRASH: {
      volatile int* volatile nowhere = NULL;
      *nowhere = 1;
      break;
    }
    case FAULT_ABORT: abort();
    case FAULT_EXIT: exit(0);
    case FAULT_HANG: {
      volatile unsigned long spins = 0;
      for (;;) ++spins;
    }
    case FAULT_NONE:
    case FAULT_FAIL:
    case FAULT_CHOSEN: break;
  }
}

static vsd_controller* create_kind(enum fault_kind kind, const char* const* names, const double* values, int count,
                                   char* error, int error_size) {
  vsd_controller* self = (vsd_controller*)calloc(1, sizeof(vsd_controller));
  if (self == NULL) {
    snprintf(error, (size_t)error_size, "out of memory");
    return NULL;
  }
  self->kind = kind;
  self->armed = 1;
  self->at = 0.0;
  for (int i = 0; i < count; ++i) {
    if (strcmp(names[i], "fault") == 0) {
      self->armed = values[i] != 0.0;
    } else if (strcmp(names[i], "at") == 0) {
      self->at = values[i];
    } else if (kind == FAULT_CHOSEN && strcmp(names[i], "kind") == 0) {
      if (values[i] < 0.0 || values[i] > 5.0 || values[i] != floor(values[i])) {
        snprintf(error, (size_t)error_size, "parameter 'kind' = %g: expected 0 .. 5", values[i]);
        free(self);
        return NULL;
      }
      self->kind = (enum fault_kind)(int)values[i];
    } else {
      snprintf(error, (size_t)error_size, "unknown parameter '%s' (known: fault, at%s)", names[i],
               kind == FAULT_CHOSEN ? ", kind" : "");
      free(self);
      return NULL;
    }
  }
  if (self->kind == FAULT_CHOSEN) self->kind = FAULT_NONE;
  if (self->kind == FAULT_NONE) self->armed = 0;
  if (self->armed && self->at < 0.0) strike(self->kind);
  return self;
}

static void reset(vsd_controller* self) { (void)self; }

static int step(vsd_controller* self, const vsd_observation* obs, double dt, vsd_command* command) {
  (void)dt;
  if (self->armed && obs->time + 1e-9 >= self->at) {
    strike(self->kind);
    return 1; /* FAULT_FAIL: an ordinary error */
  }
  command->accel = 0.0;
  if (obs->has_leader) {
    const double wanted = 2.0 + 2.0 * obs->speed;
    command->accel = 0.3 * (obs->leader_gap - wanted) + 0.8 * (obs->leader_speed - obs->speed);
  }
  command->curvature = 0.0;
  if (obs->has_lane) {
    const double x = obs->preview_x[1];
    const double y = obs->preview_y[1];
    const double distance_sq = x * x + y * y;
    if (distance_sq > 1e-6) command->curvature = 2.0 * y / distance_sq;
  }
  return 0;
}

static void destroy(vsd_controller* self) { free(self); }

#define DEFINE_KIND(fn, kind)                                                                              \
  static vsd_controller* fn(const char* const* names, const double* values, int count, char* error,       \
                            int error_size) {                                                              \
    return create_kind(kind, names, values, count, error, error_size);                                     \
  }
DEFINE_KIND(create_crash, FAULT_CRASH)
DEFINE_KIND(create_abort, FAULT_ABORT)
DEFINE_KIND(create_exit, FAULT_EXIT)
DEFINE_KIND(create_hang, FAULT_HANG)
DEFINE_KIND(create_fail, FAULT_FAIL)
DEFINE_KIND(create_chosen, FAULT_CHOSEN)

static const vsd_controller_api kApis[] = {
    {VSD_CONTROLLER_ABI_VERSION, "crashing_ego", "segfaults when its fault strikes", create_crash, reset, step, destroy},
    {VSD_CONTROLLER_ABI_VERSION, "aborting_ego", "calls abort() when its fault strikes", create_abort, reset, step,
     destroy},
    {VSD_CONTROLLER_ABI_VERSION, "exiting_ego", "calls exit(0) when its fault strikes", create_exit, reset, step,
     destroy},
    {VSD_CONTROLLER_ABI_VERSION, "hanging_ego", "loops forever when its fault strikes", create_hang, reset, step,
     destroy},
    {VSD_CONTROLLER_ABI_VERSION, "failing_ego", "returns an error status when its fault strikes", create_fail, reset,
     step, destroy},
    {VSD_CONTROLLER_ABI_VERSION, "misbehaving_ego", "the fault given by the parameter 'kind'", create_chosen, reset, step,
     destroy},
};

__attribute__((visibility("default"))) const vsd_controller_api* vsd_controller_entry(int index) {
  if (index < 0 || index >= (int)(sizeof(kApis) / sizeof(kApis[0]))) return NULL;
  return &kApis[index];
}
