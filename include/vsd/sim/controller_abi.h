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
 *
 * Versions. A controller declares the version it was written for in
 * abi_version; vsd-sumo loads every version from VSD_CONTROLLER_ABI_MIN_VERSION
 * to VSD_CONTROLLER_ABI_VERSION and fills what that version knows:
 *   1  the Ego's state, its lane, SUMO's leader (has_leader ...);
 *   2  + the object list (object_count, objects): every road user within the
 *        scenario's sensor coverage, with its relation to the Ego's lane and path.
 * A newer version only appends fields to vsd_observation, so a controller built
 * against an older header reads the same fields at the same places (a version-1
 * controller gets object_count = 0 and objects = NULL). A scenario that relies
 * on version-2 data (e.g. sets the Ego's sensor) refuses a version-1 controller.
 */
#ifndef VSD_SIM_CONTROLLER_ABI_H
#define VSD_SIM_CONTROLLER_ABI_H

#ifdef __cplusplus
extern "C" {
#endif

#define VSD_CONTROLLER_ABI_VERSION 2     /* the version this header describes */
#define VSD_CONTROLLER_ABI_MIN_VERSION 1 /* the oldest version vsd-sumo still loads */
#define VSD_PREVIEW_POINTS 10

/* Kinds of road users (the order of vsd::RoadUserType, include/vsd/core/road_user.hpp). */
enum {
  VSD_OBJECT_CAR = 0,
  VSD_OBJECT_VAN = 1,
  VSD_OBJECT_TRUCK = 2,
  VSD_OBJECT_BUS = 3,
  VSD_OBJECT_MOTORBIKE = 4,
  VSD_OBJECT_PEDESTRIAN = 5,
  VSD_OBJECT_STATIONARY = 6,
  VSD_OBJECT_BICYCLE = 7 /* appended: a plugin built before it sees an unknown kind */
};

/* One road user of the object list (version 2). The relation fields follow
 * vsd::relateToPath (include/vsd/core/path_relation.hpp): the reference line is
 * the centre line of the Ego's lane, the Ego's path the corridor of its own
 * width that it sweeps along that line at its own lateral offset. */
typedef struct vsd_object {
  int id;   /* > 0, the road user's place in its scenario (stable over the scenario) */
  int type; /* VSD_OBJECT_* */
  double x, y;          /* m, centre */
  double heading;       /* rad */
  double speed;         /* m/s, >= 0 */
  double accel;         /* m/s^2, longitudinal */
  double length, width; /* m */

  double longitudinal_distance; /* m, along the Ego's lane, centre to centre, > 0 ahead */
  double longitudinal_gap;      /* m, bumper to bumper along the lane; < 0 side by side */
  double lateral_distance;      /* m, across the lane, centre to centre, > 0 left of the Ego */
  double lateral_gap;           /* m, side to side; < 0: it reaches into the Ego's path */
  double lane_offset;           /* m, its centre from the Ego's lane centre line, > 0 left */
  double relative_heading;      /* rad, its heading minus the lane's direction */
  int relative_lane;            /* lane of its centre: 0 the Ego's, +1 next left, -1 next right */
  int in_path;                  /* 1: ahead and reaching into the Ego's path */
} vsd_object;

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
  double leader_speed; /* m/s along the lane (< 0: it drives against it, towards the Ego) */
  double leader_accel; /* m/s^2 along the lane */

  /* Version 2 and later: the object list (see vsd_object) in the scenario's
   * order of road users; the array is valid only during the step() call. */
  int object_count;
  const vsd_object* objects;
} vsd_observation;

typedef struct vsd_command {
  double accel;     /* m/s^2, longitudinal (the vehicle model clamps it to its limits) */
  double curvature; /* 1/m, path curvature, > 0 turns left */
} vsd_command;

/* Opaque instance type, defined by the plugin. */
typedef struct vsd_controller vsd_controller;

typedef struct vsd_controller_api {
  int abi_version;         /* the version the controller is written for (VSD_CONTROLLER_ABI_VERSION) */
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
