/* The Arduino's motor controller logic: see ff_motor.h and ../PROTOCOL.md. */
#include "ff_motor.h"

#include <string.h>

#include "ff_protocol.h"

void ff_pid_defaults(ff_pid_gains *g) {
  g->kp = 2.5f;
  g->ki = 25.0f;
  g->kd = 0.005f;
  g->tf = 0.01f;
  g->b = 0.5f;
  g->tt = 0.1f;
  g->limit = 12.0f;
}

float ff_pid_step(ff_pid *s, const ff_pid_gains *g, float r, float y, float dt_s) {
  float d = (g->tf * s->derivative - g->kd * (y - s->last)) / (g->tf + dt_s);
  float u = g->kp * (g->b * r - y) + s->integral + d;
  float u_sat = u < -g->limit ? -g->limit : (u > g->limit ? g->limit : u);
  s->integral += dt_s * (g->ki * (r - y) + (u_sat - u) / g->tt);
  s->derivative = d;
  s->last = y;
  return u_sat;
}

void ff_motor_init(ff_motor *m, const ff_pid_gains *g, float counts_per_rev, float supply_v,
                   uint32_t now_us) {
  memset(m, 0, sizeof *m);
  m->gains = *g;
  m->counts_per_rad = counts_per_rev / 6.28318530718f;
  m->supply_v = supply_v;
  m->last_command_us = now_us;
  m->flags = FF_WATCHDOG_TRIPPED; /* no command yet: motors off */
}

static int16_t ff_i16(const uint8_t *p) { return (int16_t)(uint16_t)(p[0] | (p[1] << 8)); }

void ff_motor_command(ff_motor *m, uint8_t type, const uint8_t *payload, uint8_t n,
                      uint32_t now_us) {
  if (type == FF_ESTOP && n == 0) {
    m->estop_latched = 1;
    m->flags |= FF_ESTOP_ACTIVE;
    m->mode = 0;
    return;
  }
  if (type == FF_ESTOP_CLEAR && n == 0) {
    m->estop_latched = 0;
    m->flags &= (uint8_t)~FF_ESTOP_ACTIVE;
    return;
  }
  if ((type != FF_SETPOINT && type != FF_PWM) || n != 4) return;
  m->last_command_us = now_us;
  m->flags &= (uint8_t)~FF_WATCHDOG_TRIPPED;
  if (m->estop_latched) return; /* refreshes the watchdog, moves nothing */
  if (type == FF_SETPOINT) {
    if (m->mode != 1) memset(m->pid, 0, sizeof m->pid);
    m->mode = 1;
    m->ref_rad_s[0] = ff_i16(payload) / 1000.0f;
    m->ref_rad_s[1] = ff_i16(payload + 2) / 1000.0f;
  } else {
    m->mode = 2;
    m->duty[0] = ff_i16(payload) / 1000.0f;
    m->duty[1] = ff_i16(payload + 2) / 1000.0f;
  }
}

void ff_motor_tick(ff_motor *m, uint32_t now_us, const int32_t counts[2], float volts[2]) {
  /* the counts of the last FF_WINDOW + 1 periods, oldest first (the first fills all) */
  if (!m->filled) {
    for (int k = 0; k <= FF_WINDOW; ++k) {
      m->history[k][0] = counts[0];
      m->history[k][1] = counts[1];
    }
    m->filled = 1;
  } else {
    memmove(m->history[0], m->history[1], sizeof m->history - sizeof m->history[0]);
    m->history[FF_WINDOW][0] = counts[0];
    m->history[FF_WINDOW][1] = counts[1];
  }
  /* unsigned difference: correct across the wrap of micros() */
  if ((uint32_t)(now_us - m->last_command_us) > FF_WATCHDOG_US) {
    m->flags |= FF_WATCHDOG_TRIPPED;
    m->mode = 0;
  }
  float dt_s = FF_PERIOD_US * 1e-6f;
  for (int w = 0; w < 2; ++w) {
    float speed = (float)(m->history[FF_WINDOW][w] - m->history[0][w]) /
                  (m->counts_per_rad * FF_WINDOW * dt_s);
    if (m->mode == 1) {
      volts[w] = ff_pid_step(&m->pid[w], &m->gains, m->ref_rad_s[w], speed, dt_s);
    } else {
      if (m->mode == 2) {
        volts[w] = m->duty[w] * m->supply_v;
      } else {
        volts[w] = 0.0f;
      }
      m->pid[w].last = speed;
    }
  }
}
