/* DO NOT EDIT: written by `make embedded` from the controllers in quadcog/controllers/; change those and re-export. */
/* quadcog_geometric: GeometricAdaptive (quadcog.controllers.geometric) as a
 * C99 module in float (float32)
 *
 * Designed for: a control period of dt = 0.001 s (1000 Hz), fed the state estimate
 * at the start of the period; U is held over the period. Frames and signs: ground frame
 * {G} inertial, z up,
 * gravity -g e_z; body frame {A} with origin O at the rotor-plane centre, x forward, z up
 * along the thrust (a z-down NED/FRD estimate must be converted: see the README, "On a
 * flight controller"); ZYX Euler angles, R = Rz(psi) Ry(theta) Rx(phi) maps body to ground.
 * x (12) = [x, y, z, phi, theta, psi, u, v, w, p, q, r]: position of O (m, ground),
 *   Euler angles (rad), body velocities u, v, w (m/s, body axes), body rates p, q, r (rad/s).
 * ref (14) = position (3, m), velocity (3, m/s), acceleration (3, m/s^2), jerk (3, m/s^3),
 *   all in the ground frame, then yaw (rad) and yaw rate (rad/s).
 * U (4) = [U1 thrust along body z (N), U2, U3, U4 body moments about O (N m)]; map to rotor
 *   thrusts with the inverse of the vehicle's mixer.
 * c (78) = the controller state (78 entries; the adaptive laws: r_hat, the CoG estimate, m, body axes).
 *   quadcog_geometric_init sets it to [0, 0, 0, 0.68, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]
 *
 * Nominal vehicle parameters baked into the code (the controller's model):
 *   m        = 0.68 kg
 *   g        = 9.81 m/s^2
 *   Ixx      = 0.007 kg m^2
 *   Iyy      = 0.007 kg m^2
 *   Izz      = 0.012 kg m^2
 *   c_x      = 0.1 N s/m
 *   c_y      = 0.1 N s/m
 *   c_z      = 0.1 N s/m
 *   c_phi    = 0.001 N m s/rad
 *   c_theta  = 0.001 N m s/rad
 *   c_psi    = 0.001 N m s/rad
 *   x_G      = 0 m
 *   y_G      = 0 m
 *   z_G      = 0 m
 * Gains and settings baked into the code (SI units: m, s, rad, N):
 *   clock_stop = 1
 *   cone = [3.27533, 0, 0; 0, 3.27533, 0; 0, 0, 19.652]
 *   consistency_margin = 0.1
 *   covariance_bound = 1
 *   filter_rate = 20
 *   force_weight = 1
 *   forgetting = 8
 *   gamma = 0
 *   inertia = [0.007, 0, 0.007, 0, 0, 0.012]
 *   k_R = 120
 *   k_W = 22
 *   k_v = 7
 *   k_x = 12
 *   ls_gain = 200
 *   mass_bounds = [0.5, 3.59968]
 *   motor_states = 0
 *   n_estimator = 75
 *   n_state = 78
 *   parameter_scale = [0.68, 0.1156, 0.1156, 0.1156]
 *   rate_filter = 80
 *   row_scale = [0.149907, 0.149907, 0.149907, 0.881806, 0.881806, 0.881806]
 *   row_weight = [200, 200, 200, 200, 200, 200]
 *   sigma_inverse = [166.667, 0, 0; 0, 166.667, 0; 0, 0, 1000]
 *   warm_up = 0
 *
 * No heap, no globals, no I/O; only <math.h>. Re-entrant: all state is in c[].
 */
#ifndef QUADCOG_GEOMETRIC_H
#define QUADCOG_GEOMETRIC_H

#ifndef QUADCOG_REAL_IS_FLOAT
#define QUADCOG_REAL_IS_FLOAT 1
typedef float qc_real;
#elif QUADCOG_REAL_IS_FLOAT != 1
#error "quadcog modules of different precisions included in one translation unit"
#endif

/* size of the controller state c */
#define QUADCOG_GEOMETRIC_NC 78

#ifdef __cplusplus
extern "C" {
#endif

/* c has max(QUADCOG_GEOMETRIC_NC, 1) entries */
void quadcog_geometric_init(qc_real c[]);

/* One control period: state x (12), reference ref (14), controller state c (updated in
   place by one Euler step of length dt, projection included), output U (4). */
void quadcog_geometric_step(const qc_real x[12], const qc_real ref[14], qc_real c[],
                            qc_real dt, qc_real U[4]);

#ifdef __cplusplus
}
#endif

#endif /* QUADCOG_GEOMETRIC_H */
