/* The Arduino's motor controller logic, hardware-free (plain C99): commands, watchdog,
 * e-stop and the wheel-speed PID of the deliverable's section 2.6.4 at 100 Hz. The sketch
 * feeds it the time, the decoded frames and the encoder counts, and applies the
 * voltages it returns; the host tests run the same code. See ../PROTOCOL.md. */
#ifndef FF_MOTOR_H
#define FF_MOTOR_H

#include <stdint.h>

#define FF_WATCHDOG_US 200000UL
#define FF_PERIOD_US 10000UL
#define FF_WINDOW 2 /* speed = count difference over 2 periods (20 ms) */

/* firefleet.control.pid.PidParams, same law and defaults (Table 2 motor, 10 ms). */
typedef struct {
  float kp, ki, kd, tf, b, tt, limit;
} ff_pid_gains;

typedef struct {
  float integral, derivative, last;
} ff_pid;

typedef struct {
  ff_pid_gains gains;
  ff_pid pid[2];
  float counts_per_rad;
  float supply_v;
  int32_t history[FF_WINDOW + 1][2]; /* counts of the last FF_WINDOW + 1 periods */
  uint8_t filled;
  float ref_rad_s[2];
  float duty[2];
  uint8_t mode; /* 0 stopped, 1 speed (PID), 2 open-loop duty */
  uint8_t flags; /* FF_WATCHDOG_TRIPPED | FF_ESTOP_ACTIVE | FF_SUPPLY_LOW */
  uint8_t estop_latched;
  uint32_t last_command_us;
} ff_motor;

void ff_pid_defaults(ff_pid_gains *g);

/* One PID period: the saturated output [V] (firefleet.control.pid.pid_step). */
float ff_pid_step(ff_pid *s, const ff_pid_gains *g, float r, float y, float dt_s);

void ff_motor_init(ff_motor *m, const ff_pid_gains *g, float counts_per_rev, float supply_v,
                   uint32_t now_us);

/* A decoded frame from the Pi (SETPOINT, PWM, ESTOP, ESTOP_CLEAR; others ignored). */
void ff_motor_command(ff_motor *m, uint8_t type, const uint8_t *payload, uint8_t n,
                      uint32_t now_us);

/* The 100 Hz period: counts read now; writes the voltages to apply [V]. */
void ff_motor_tick(ff_motor *m, uint32_t now_us, const int32_t counts[2], float volts[2]);

#endif
