#include "state_envelope.h"

#include <stdio.h>
#include <string.h>

static const char MAGIC[8] = {'F', 'M', 'U', 'S', 'T', 'A', 'T', 'E'};

uint32_t crc32_of(const unsigned char *data, size_t size) {
    uint32_t crc = 0xFFFFFFFFu;
    for (size_t i = 0; i < size; i++) {
        crc ^= data[i];
        for (int bit = 0; bit < 8; bit++) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return crc ^ 0xFFFFFFFFu;
}

static void put32(unsigned char *out, uint32_t value) {
    for (int i = 0; i < 4; i++) out[i] = (unsigned char)(value >> (8 * i));
}

static uint32_t get32(const unsigned char *in) {
    return (uint32_t)in[0] | (uint32_t)in[1] << 8 | (uint32_t)in[2] << 16 | (uint32_t)in[3] << 24;
}

static void put_field(unsigned char *out, const char *text) {
    memset(out, 0, ENVELOPE_FIELD);
    size_t n = strlen(text);
    memcpy(out, text, n < ENVELOPE_FIELD - 1 ? n : ENVELOPE_FIELD - 1);
}

void envelope_write(unsigned char *out, const char *name, const char *guid, uint32_t version,
                    const unsigned char *payload, size_t length) {
    memcpy(out, MAGIC, sizeof MAGIC);
    put32(out + 8, version);
    put32(out + 12, (uint32_t)length);
    put_field(out + 16, name);
    put_field(out + 16 + ENVELOPE_FIELD, guid);
    memcpy(out + 16 + 2 * ENVELOPE_FIELD, payload, length);
    size_t end = 16 + 2 * ENVELOPE_FIELD + length;
    put32(out + end, crc32_of(out, end));
}

int envelope_read(const unsigned char *in, size_t size, const char *name, const char *guid,
                  uint32_t version, const unsigned char **payload, size_t *length,
                  char *problem, size_t problem_size) {
    const char *cannot = "the serialized state cannot be read";
    if (in == NULL) {
        snprintf(problem, problem_size, "%s: the buffer is NULL", cannot);
        return 1;
    }
    if (size < ENVELOPE_OVERHEAD || memcmp(in, MAGIC, sizeof MAGIC) != 0) {
        snprintf(problem, problem_size, "%s: %u bytes that do not begin with an FMU state "
                 "header", cannot, (unsigned)size);
        return 1;
    }
    size_t declared = get32(in + 12);
    if (declared != size - ENVELOPE_OVERHEAD) {
        snprintf(problem, problem_size, "%s: it declares %u bytes of content but carries %u "
                 "(truncated or padded)", cannot, (unsigned)declared,
                 (unsigned)(size - ENVELOPE_OVERHEAD));
        return 1;
    }
    if (get32(in + size - 4) != crc32_of(in, size - 4)) {
        snprintf(problem, problem_size, "%s: its checksum does not match (corrupted)", cannot);
        return 1;
    }
    char their_name[ENVELOPE_FIELD], their_guid[ENVELOPE_FIELD];
    memcpy(their_name, in + 16, ENVELOPE_FIELD);
    memcpy(their_guid, in + 16 + ENVELOPE_FIELD, ENVELOPE_FIELD);
    their_name[ENVELOPE_FIELD - 1] = their_guid[ENVELOPE_FIELD - 1] = '\0';
    if (strcmp(their_name, name) != 0 || strcmp(their_guid, guid) != 0) {
        snprintf(problem, problem_size, "the state belongs to '%s' (GUID %s), not to %s "
                 "(GUID %s)", their_name, their_guid, name, guid);
        return 1;
    }
    if (get32(in + 8) != version) {
        snprintf(problem, problem_size, "%s: it has format version %u, this FMU reads version "
                 "%u", cannot, (unsigned)get32(in + 8), (unsigned)version);
        return 1;
    }
    *payload = in + 16 + 2 * ENVELOPE_FIELD;
    *length = declared;
    return 0;
}
