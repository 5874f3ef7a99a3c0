/* The motor link's frames, version 1: see ../PROTOCOL.md (the one description).
 * Plain C99, no Arduino headers: the sketch includes it, and the Python tests compile
 * it on the host to check that both sides encode and decode the same bytes. */
#ifndef FF_PROTOCOL_H
#define FF_PROTOCOL_H

#include <stddef.h>
#include <stdint.h>

#define FF_SYNC1 0xA5
#define FF_SYNC2 0x5A
#define FF_MAX_PAYLOAD 32
#define FF_FRAME_OVERHEAD 6

enum {
  FF_SETPOINT = 0x01,
  FF_PWM = 0x02,
  FF_ESTOP = 0x03,
  FF_ESTOP_CLEAR = 0x04,
  FF_ENCODERS = 0x81,
  FF_STATUS = 0x82
};

enum { FF_WATCHDOG_TRIPPED = 0x01, FF_ESTOP_ACTIVE = 0x02, FF_SUPPLY_LOW = 0x04 };

/* CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, no reflection, no final XOR. */
uint16_t ff_crc16(const uint8_t *data, size_t n);

/* Writes the frame of (type, payload[n]) to out (n + 6 bytes); returns its length,
 * or 0 when n > FF_MAX_PAYLOAD. */
size_t ff_encode(uint8_t type, const uint8_t *payload, uint8_t n, uint8_t *out);

/* The expected payload length of a type, or -1 for an unknown type. */
int ff_expected_length(uint8_t type);

/* A streaming decoder: feed one byte at a time. */
typedef struct {
  uint8_t buf[FF_MAX_PAYLOAD + FF_FRAME_OVERHEAD];
  uint8_t len; /* bytes held in buf */
  uint16_t crc_errors;
  uint16_t framing_errors;
} ff_decoder;

void ff_decoder_init(ff_decoder *d);

/* Feeds one byte. Returns 1 and sets *type, payload (FF_MAX_PAYLOAD bytes) and *n when
 * the byte completes a valid frame; 0 otherwise. A dropped frame's bytes after its first
 * sync byte are searched again for a sync, as PROTOCOL.md requires. */
int ff_decoder_feed(ff_decoder *d, uint8_t byte, uint8_t *type, uint8_t *payload, uint8_t *n);

/* Checks the bytes already held for a complete frame (a frame found behind a dropped
 * one may be followed by the start of the next): same results as ff_decoder_feed. */
int ff_decoder_poll(ff_decoder *d, uint8_t *type, uint8_t *payload, uint8_t *n);

#endif
