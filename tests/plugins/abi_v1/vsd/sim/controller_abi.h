/*
 * C ABI for Ego controllers in shared libraries (plugins).
 *
 * A plugin library exports one function:
 *
 *     const vsd_controller_api* vsd_controller_entry(int index);
 *
 * returning its controllers for index = 0, 1, ... and NULL past the last one.
 * The scenario YAML selects a controller by name and library:
 *
 *     controller: {name: my_ego, library: build/libmy_ego.so, params: {k: 0.5}}
 *
 * Units: SI (m, s, m/s, m/s^2, rad, 1/m). Frame: the scenario frame (x along
 * the road, y left); headings are mathematical (0 = +x, counter-clockwise).
 * The vehicle reference point is the centre of the vehicle.
 *
 * Lifecycle: create() once per concrete scenario with its evaluated
 * parameters, reset() before the first step, step() every time step,
 * destroy() at the end. Calls for one instance come from one thread.
 */
#ifndef VSD_SIM_CONTROLLER_ABI_H
#define VSD_SIM_CONTROLLER_ABI_H

#ifdef __cplusplus
extern "C" {
#endif

#define VSD_CONTROLLER_ABI_VERSION 1
#define VSD_PREVIEW_POINTS 10

typedef struct vsd_observation {
  double time; /* s since the scenario started */

  /* The Ego itself. */
  double x, y;    /* m, centre */
  double heading; /* rad */
  double speed;   /* m/s */
  double accel;   /* m/s^2, over the last step */
  double length, width; /* m */

  /* The lane the Ego is on (has_lane = 0 when it is off the road). */
  int has_lane;
  double lane_lateral_offset; /* m, Ego centre relative to the lane centre, > 0 left */
  double lane_heading_error;  /* rad, Ego heading minus lane direction */
  double lane_width;          /* m */
  double preview_spacing;     /* m between preview points along the lane */
  /* Lane centre at preview_spacing * (i + 1) m ahead, in the Ego frame (x forward, y left). */
  double preview_x[VSD_PREVIEW_POINTS];
  double preview_y[VSD_PREVIEW_POINTS];

  /* The vehicle ahead on the Ego's lane (has_leader = 0 when there is none within range). */
  int has_leader;
  double leader_gap;   /* m, bumper to bumper along the lane */
  double leader_speed; /* m/s */
  double leader_accel; /* m/s^2 */
} vsd_observation;

typedef struct vsd_command {
  double accel;     /* m/s^2, longitudinal (the vehicle model clamps it to its limits) */
  double curvature; /* 1/m, path curvature, > 0 turns left */
} vsd_command;

/* Opaque instance type, defined by the plugin. */
typedef struct vsd_controller vsd_controller;

typedef struct vsd_controller_api {
  int abi_version;         /* VSD_CONTROLLER_ABI_VERSION */
  const char* name;        /* unique name used in scenario files */
  const char* description; /* one line */
  /* Returns a new instance or NULL; on NULL writes a one-line reason into error. */
  vsd_controller* (*create)(const char* const* param_names, const double* param_values, int param_count,
                            char* error, int error_size);
  void (*reset)(vsd_controller* self);
  /* Returns 0 on success; non-zero marks the scenario as failed. */
  int (*step)(vsd_controller* self, const vsd_observation* observation, double dt, vsd_command* command);
  void (*destroy)(vsd_controller* self);
} vsd_controller_api;

typedef const vsd_controller_api* (*vsd_controller_entry_fn)(int index);

#ifdef __cplusplus
}
#endif

#endif /* VSD_SIM_CONTROLLER_ABI_H */
