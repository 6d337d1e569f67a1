/* DO NOT EDIT: written by `make embedded` from the controllers in quadcog/controllers/; change those and re-export. */
/* quadcog_pd: CascadePD (quadcog.controllers.cascade_pd) as a
 * C99 module in double (double)
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
 * c (1) = the controller state (NC = 0: unused, pass any 1-entry array).
 *   quadcog_pd_init writes 0.
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
 *   B = [0, 0, 0, 0; 0, 0, 0, 0; 0, 0, 0, 0; 0, 0, 0, 0; 0, 0, 0, 0; 0, 0, 0, 0; 0, 0, 0,
 *       0; 0, 0, 0, 0; 1.47059, 0, 0, 0; 0, 142.857, 0, 0; 0, 0, 142.857, 0; 0, 0, 0, 83.3333]
 *   K = [0, 0, 8.16, 0, 0, 0, 0, 0, 4.66, 0, 0, 0; 0, -0.428135, 0, 1.54087, 0, 0, 0,
 *       -0.440714, 0, 0.183471, 0, 0; 0.428135, 0, 0, 0, 1.54087, 0, 0.440714, 0, 0, 0,
 *       0.183471, 0; 0, 0, 0, 0, 0, 0.24, 0, 0, 0, 0, 0, 0.107]
 *   closed_loop_eigenvalues = [-12, -12, -10, -10, -5, -4, -4, -3, -2.5, -2.5, -2, -2]
 *   gains[z] = [8.16, 4.66]
 *   gains[psi] = [0.24, 0.107]
 *   gains[x] = [0.428135, 0.440714, 1.54087, 0.183471]
 *   gains[y] = [-0.428135, -0.440714, 1.54087, 0.183471]
 *   hover_input = [6.6708, 0, 0, 0]
 *   max_tilt = 0.6
 *   poles[z] = [-3, -4]
 *   poles[psi] = [-4, -5]
 *   poles[x] = [-2, -2.5, -10, -12]
 *   poles[y] = [-2, -2.5, -10, -12]
 *
 * No heap, no globals, no I/O; only <math.h>. Re-entrant: all state is in c[].
 */
#ifndef QUADCOG_PD_H
#define QUADCOG_PD_H

#ifndef QUADCOG_REAL_IS_FLOAT
#define QUADCOG_REAL_IS_FLOAT 0
typedef double qc_real;
#elif QUADCOG_REAL_IS_FLOAT != 0
#error "quadcog modules of different precisions included in one translation unit"
#endif

/* size of the controller state c */
#define QUADCOG_PD_NC 0

#ifdef __cplusplus
extern "C" {
#endif

/* c has max(QUADCOG_PD_NC, 1) entries */
void quadcog_pd_init(qc_real c[]);

/* One control period: state x (12), reference ref (14), controller state c (updated in
   place by one Euler step of length dt, projection included), output U (4). */
void quadcog_pd_step(const qc_real x[12], const qc_real ref[14], qc_real c[],
                     qc_real dt, qc_real U[4]);

#ifdef __cplusplus
}
#endif

#endif /* QUADCOG_PD_H */
