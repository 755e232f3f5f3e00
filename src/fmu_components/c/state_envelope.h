/*
 * A serialized FMU state, for both flavours' binaries:
 *
 *   "FMUSTATE" | format version | payload length | model name | GUID | payload | CRC-32
 *
 * (integers as 4 bytes little-endian, name and GUID in 64 bytes each, NUL-padded; the
 * CRC-32 is zlib's, over everything before it). A state from another FMU, another build of
 * it, another format version, or one that is truncated or corrupted is refused before
 * anything of it is used.
 */
#ifndef STATE_ENVELOPE_H
#define STATE_ENVELOPE_H

#include <stddef.h>
#include <stdint.h>

#define ENVELOPE_FIELD 64
#define ENVELOPE_OVERHEAD (8 + 4 + 4 + 2 * ENVELOPE_FIELD + 4)

uint32_t crc32_of(const unsigned char *data, size_t size);

/* Write payload[length] in its envelope to out[length + ENVELOPE_OVERHEAD]. */
void envelope_write(unsigned char *out, const char *name, const char *guid, uint32_t version,
                    const unsigned char *payload, size_t length);

/* 0 with the payload's place and length, or 1 with the reason in problem[size]. */
int envelope_read(const unsigned char *in, size_t size, const char *name, const char *guid,
                  uint32_t version, const unsigned char **payload, size_t *length,
                  char *problem, size_t problem_size);

#endif
