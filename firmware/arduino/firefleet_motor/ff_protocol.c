/* The motor link's frames, version 1: see ../PROTOCOL.md and ff_protocol.h. */
#include "ff_protocol.h"

#include <string.h>

uint16_t ff_crc16(const uint8_t *data, size_t n) {
  uint16_t crc = 0xFFFF;
  for (size_t i = 0; i < n; ++i) {
    crc ^= (uint16_t)data[i] << 8;
    for (int b = 0; b < 8; ++b) {
      crc = (crc & 0x8000) ? (uint16_t)((crc << 1) ^ 0x1021) : (uint16_t)(crc << 1);
    }
  }
  return crc;
}

size_t ff_encode(uint8_t type, const uint8_t *payload, uint8_t n, uint8_t *out) {
  if (n > FF_MAX_PAYLOAD) return 0;
  out[0] = FF_SYNC1;
  out[1] = FF_SYNC2;
  out[2] = n;
  out[3] = type;
  if (n) memcpy(out + 4, payload, n);
  uint16_t crc = ff_crc16(out + 2, (size_t)n + 2);
  out[4 + n] = (uint8_t)(crc & 0xFF);
  out[5 + n] = (uint8_t)(crc >> 8);
  return (size_t)n + FF_FRAME_OVERHEAD;
}

int ff_expected_length(uint8_t type) {
  switch (type) {
    case FF_SETPOINT: return 4;
    case FF_PWM: return 4;
    case FF_ESTOP: return 0;
    case FF_ESTOP_CLEAR: return 0;
    case FF_ENCODERS: return 12;
    case FF_STATUS: return 6;
    default: return -1;
  }
}

void ff_decoder_init(ff_decoder *d) { memset(d, 0, sizeof *d); }

/* Drops the first byte held and re-hunts a sync in what is left. */
static void ff_resync(ff_decoder *d) {
  uint8_t i = 1;
  while (i < d->len && d->buf[i] != FF_SYNC1) ++i;
  memmove(d->buf, d->buf + i, d->len - i);
  d->len = (uint8_t)(d->len - i);
}

/* Checks what is held: 1 frame complete, 0 need more, -1 dropped (re-check). */
static int ff_check(ff_decoder *d, uint8_t *type, uint8_t *payload, uint8_t *n) {
  if (d->len >= 1 && d->buf[0] != FF_SYNC1) { ff_resync(d); return -1; }
  if (d->len >= 2 && d->buf[1] != FF_SYNC2) { ff_resync(d); return -1; }
  if (d->len < 4) return 0;
  uint8_t len = d->buf[2];
  int expected = ff_expected_length(d->buf[3]);
  if (len > FF_MAX_PAYLOAD || (expected >= 0 && expected != len)) {
    ++d->framing_errors;
    ff_resync(d);
    return -1;
  }
  if (d->len < len + FF_FRAME_OVERHEAD) return 0;
  uint16_t crc = (uint16_t)(d->buf[4 + len] | (d->buf[5 + len] << 8));
  if (crc != ff_crc16(d->buf + 2, (size_t)len + 2)) {
    ++d->crc_errors;
    ff_resync(d);
    return -1;
  }
  *type = d->buf[3];
  *n = len;
  if (len) memcpy(payload, d->buf + 4, len);
  uint8_t used = (uint8_t)(len + FF_FRAME_OVERHEAD);
  memmove(d->buf, d->buf + used, d->len - used);
  d->len = (uint8_t)(d->len - used);
  return 1;
}

int ff_decoder_poll(ff_decoder *d, uint8_t *type, uint8_t *payload, uint8_t *n) {
  while (d->len > 0) {
    int r = ff_check(d, type, payload, n);
    if (r >= 0) return r;
  }
  return 0;
}

int ff_decoder_feed(ff_decoder *d, uint8_t byte, uint8_t *type, uint8_t *payload, uint8_t *n) {
  if (d->len == 0 && byte != FF_SYNC1) return 0;
  if (d->len == sizeof d->buf) ff_resync(d); /* cannot happen with a checked length */
  d->buf[d->len++] = byte;
  return ff_decoder_poll(d, type, payload, n);
}
