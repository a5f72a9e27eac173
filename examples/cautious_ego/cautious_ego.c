/*
 * Example Ego controller plugin for vsd-sumo, written in plain C against
 * include/vsd/sim/controller_abi.h.
 *
 * `cautious_ego` keeps a long time gap and steers with a state-feedback lane
 * keeper (lateral offset + heading error + lane curvature from the preview):
 *
 *   accel     = min(k_speed (set_speed - v),
 *                   k_gap (gap - (standstill_gap + time_gap v)) + k_speed (v_leader - v))
 *   curvature = kappa_lane - k_offset * lateral_offset - k_heading * heading_error
 *
 * The leader is the nearest road user of the object list in the Ego's path
 * (ABI version 2); built against a version-1 header (no object list) it is
 * SUMO's leader (has_leader), as the tests do with tests/plugins/abi_v1/.
 *
 * Use it from a scenario file:
 *   controller: {name: cautious_ego, library: path/to/libvsd_cautious_ego.so,
 *                params: {time_gap: 3.0, set_speed: v_ego}}
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "vsd/sim/controller_abi.h"

struct vsd_controller {
  double time_gap;      /* s */
  double standstill_gap;/* m */
  double k_gap;         /* 1/s^2 */
  double k_speed;       /* 1/s */
  double k_offset;      /* 1/m^2 */
  double k_heading;     /* 1/m */
  double set_speed;     /* m/s; < 0: take the initial speed */
  double current_set_speed;
};

static const char* const kParams[] = {"time_gap", "standstill_gap", "k_gap", "k_speed", "k_offset", "k_heading",
                                      "set_speed"};

static vsd_controller* cautious_create(const char* const* names, const double* values, int count, char* error,
                                       int error_size) {
  vsd_controller* self = (vsd_controller*)calloc(1, sizeof(vsd_controller));
  if (self == NULL) {
    snprintf(error, (size_t)error_size, "out of memory");
    return NULL;
  }
  self->time_gap = 3.0;
  self->standstill_gap = 3.0;
  self->k_gap = 0.25;
  self->k_speed = 0.6;
  self->k_offset = 0.08;
  self->k_heading = 0.6;
  self->set_speed = -1.0;
  for (int i = 0; i < count; ++i) {
    double* target = NULL;
    if (strcmp(names[i], "time_gap") == 0) target = &self->time_gap;
    else if (strcmp(names[i], "standstill_gap") == 0) target = &self->standstill_gap;
    else if (strcmp(names[i], "k_gap") == 0) target = &self->k_gap;
    else if (strcmp(names[i], "k_speed") == 0) target = &self->k_speed;
    else if (strcmp(names[i], "k_offset") == 0) target = &self->k_offset;
    else if (strcmp(names[i], "k_heading") == 0) target = &self->k_heading;
    else if (strcmp(names[i], "set_speed") == 0) target = &self->set_speed;
    if (target == NULL) {
      snprintf(error, (size_t)error_size, "unknown parameter '%s' (known: %s, %s, %s, %s, %s, %s, %s)", names[i],
               kParams[0], kParams[1], kParams[2], kParams[3], kParams[4], kParams[5], kParams[6]);
      free(self);
      return NULL;
    }
    if (values[i] < 0.0 && target != &self->set_speed) {
      snprintf(error, (size_t)error_size, "parameter '%s' = %g must be >= 0", names[i], values[i]);
      free(self);
      return NULL;
    }
    *target = values[i];
  }
  self->current_set_speed = self->set_speed;
  return self;
}

static void cautious_reset(vsd_controller* self) { self->current_set_speed = self->set_speed; }

/* The leader's bumper gap and speed along the lane; 0 if there is none. */
static int find_leader(const vsd_observation* obs, double* gap, double* speed) {
#if VSD_CONTROLLER_ABI_VERSION >= 2
  int found = 0;
  for (int i = 0; i < obs->object_count; ++i) {
    const vsd_object* object = &obs->objects[i];
    if (!object->in_path || (found && object->longitudinal_gap >= *gap)) continue;
    *gap = object->longitudinal_gap;
    *speed = object->speed * cos(object->relative_heading);
    found = 1;
  }
  return found;
#else
  *gap = obs->leader_gap;
  *speed = obs->leader_speed;
  return obs->has_leader;
#endif
}

static int cautious_step(vsd_controller* self, const vsd_observation* obs, double dt, vsd_command* command) {
  (void)dt;
  if (self->current_set_speed < 0.0) self->current_set_speed = obs->speed;
  double accel = self->k_speed * (self->current_set_speed - obs->speed);
  double gap = 0.0, speed = 0.0;
  if (find_leader(obs, &gap, &speed)) {
    const double desired = self->standstill_gap + self->time_gap * obs->speed;
    const double follow = self->k_gap * (gap - desired) + self->k_speed * (speed - obs->speed);
    if (follow < accel) accel = follow;
  }
  double curvature = 0.0;
  if (obs->has_lane) {
    /* Lane curvature from the first two preview points (circle through the Ego and them). */
    const double x1 = obs->preview_x[1], y1 = obs->preview_y[1];
    const double lane_curvature = 2.0 * y1 / (x1 * x1 + y1 * y1);
    curvature = lane_curvature - self->k_offset * obs->lane_lateral_offset - self->k_heading * obs->lane_heading_error;
  }
  command->accel = accel;
  command->curvature = curvature;
  return 0;
}

static void cautious_destroy(vsd_controller* self) { free(self); }

static const vsd_controller_api kCautiousEgo = {
    VSD_CONTROLLER_ABI_VERSION,
    "cautious_ego",
    "3 s time gap + state-feedback lane keeping (example plugin)",
    cautious_create,
    cautious_reset,
    cautious_step,
    cautious_destroy,
};

__attribute__((visibility("default"))) const vsd_controller_api* vsd_controller_entry(int index) {
  return index == 0 ? &kCautiousEgo : NULL;
}
