// firefleet motor controller: the Arduino end of the motor link (../PROTOCOL.md).
// Hardware: an Arduino Uno/Nano, an L298N dual H-bridge, two gear motors with
// quadrature Hall encoders. The logic (commands, watchdog, e-stop, the 100 Hz PID) is
// ff_motor.c, shared with the host tests; this file only touches the pins.
//
// Pins (the README's wiring table):
//   right motor: ENA (PWM) D5, IN1 D7, IN2 D8;  encoder A D2 (INT0), B D4
//   left motor:  ENB (PWM) D6, IN3 D9, IN4 D10; encoder A D3 (INT1), B D11
//   supply sense: A0 through a 1:4 divider (12 V -> 3 V)
extern "C" {
#include "ff_motor.h"
#include "ff_protocol.h"
}

static const uint8_t PWM_PIN[2] = {5, 6};
static const uint8_t DIR_A[2] = {7, 9};
static const uint8_t DIR_B[2] = {8, 10};
static const uint8_t ENC_A[2] = {2, 3};
static const uint8_t ENC_B[2] = {4, 11};
static const float COUNTS_PER_REV = 2048.0f;  // 12-line Hall, x4 quadrature, ~43:1 gearing
static const float SUPPLY_DIVIDER = 4.0f;

static volatile int32_t counts[2] = {0, 0};
static ff_motor motor;
static ff_decoder decoder;
static uint32_t next_tick_us;
static uint32_t next_status_us;
static uint8_t last_flags;

// x4 quadrature on the A channel's interrupt, B read for the direction (x2 here; the
// B channel's pin-change interrupt would double it: COUNTS_PER_REV says which you wire).
static void on_right() { counts[0] += (digitalRead(ENC_A[0]) == digitalRead(ENC_B[0])) ? 1 : -1; }
static void on_left() { counts[1] += (digitalRead(ENC_A[1]) == digitalRead(ENC_B[1])) ? -1 : 1; }

static void apply(int w, float volts, float supply_v) {
  float duty = supply_v > 1.0f ? volts / supply_v : 0.0f;
  if (duty > 1.0f) duty = 1.0f;
  if (duty < -1.0f) duty = -1.0f;
  digitalWrite(DIR_A[w], duty >= 0.0f ? HIGH : LOW);
  digitalWrite(DIR_B[w], duty >= 0.0f ? LOW : HIGH);
  analogWrite(PWM_PIN[w], (int)(fabs(duty) * 255.0f + 0.5f));
}

static float supply_v() { return analogRead(A0) * (5.0f / 1023.0f) * SUPPLY_DIVIDER; }

static void send(uint8_t type, const uint8_t *payload, uint8_t n) {
  uint8_t frame[FF_MAX_PAYLOAD + FF_FRAME_OVERHEAD];
  size_t len = ff_encode(type, payload, n, frame);
  Serial.write(frame, len);
}

static void put_u32(uint8_t *p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = (uint8_t)(v >> (8 * i));
}

static void send_status(float supply) {
  uint8_t p[6];
  uint16_t mv = (uint16_t)(supply * 1000.0f);
  uint16_t errors = (uint16_t)(decoder.crc_errors + decoder.framing_errors);
  p[0] = motor.flags;
  p[1] = 0;
  p[2] = (uint8_t)mv;
  p[3] = (uint8_t)(mv >> 8);
  p[4] = (uint8_t)errors;
  p[5] = (uint8_t)(errors >> 8);
  send(FF_STATUS, p, 6);
  last_flags = motor.flags;
}

void setup() {
  Serial.begin(115200);
  for (int w = 0; w < 2; ++w) {
    pinMode(PWM_PIN[w], OUTPUT);
    pinMode(DIR_A[w], OUTPUT);
    pinMode(DIR_B[w], OUTPUT);
    pinMode(ENC_A[w], INPUT_PULLUP);
    pinMode(ENC_B[w], INPUT_PULLUP);
    apply(w, 0.0f, 12.0f);
  }
  attachInterrupt(digitalPinToInterrupt(ENC_A[0]), on_right, CHANGE);
  attachInterrupt(digitalPinToInterrupt(ENC_A[1]), on_left, CHANGE);
  ff_pid_gains gains;
  ff_pid_defaults(&gains);
  ff_motor_init(&motor, &gains, COUNTS_PER_REV, supply_v(), micros());
  ff_decoder_init(&decoder);
  next_tick_us = micros() + FF_PERIOD_US;
  next_status_us = micros();
}

void loop() {
  uint8_t type, n, payload[FF_MAX_PAYLOAD];
  while (Serial.available() > 0) {
    if (ff_decoder_feed(&decoder, (uint8_t)Serial.read(), &type, payload, &n)) {
      ff_motor_command(&motor, type, payload, n, micros());
    }
  }
  uint32_t now = micros();
  if ((int32_t)(now - next_tick_us) >= 0) {
    next_tick_us += FF_PERIOD_US;
    int32_t c[2];
    noInterrupts();
    c[0] = counts[0];
    c[1] = counts[1];
    interrupts();
    float supply = supply_v();
    motor.supply_v = supply;
    if (supply < 10.0f) motor.flags |= FF_SUPPLY_LOW; else motor.flags &= ~FF_SUPPLY_LOW;
    float volts[2];
    ff_motor_tick(&motor, now, c, volts);
    apply(0, volts[0], supply);
    apply(1, volts[1], supply);
    uint8_t p[12];
    put_u32(p, now);
    put_u32(p + 4, (uint32_t)c[0]);
    put_u32(p + 8, (uint32_t)c[1]);
    send(FF_ENCODERS, p, 12);
    if ((int32_t)(now - next_status_us) >= 0 || motor.flags != last_flags) {
      next_status_us = now + 100000UL;
      send_status(supply);
    }
  }
}
