/*
 * aerie_pose.h — shared-memory pose input for the aerie image generator (layout version 2).
 *
 * A simulator on the same host writes its ownship pose into a 144-byte file, by default
 * /dev/shm/aerie-pose (aerie: `aerie listen --protocol shm --shm-name aerie-pose`). One writer; any
 * number of readers. A seqlock guards the fields: `seq` is odd while a write is in progress and
 * even when the fields are stable (0 = never written). A CRC-32 of bytes 16..136 (flags through
 * rates) sits at offset 136; aerie drops a record whose header or checksum is wrong. Readers
 * never block the writer; they retry a read that overlapped a write.
 *
 * Compiles as C99 and later and as C++11 and later (GCC or Clang: __atomic builtins), cleanly
 * with -Wall -Wextra -pedantic. Host byte order (little-endian on x86-64 and AArch64).
 *
 *   int fd = open("/dev/shm/aerie-pose", O_RDWR | O_CREAT, 0644);   // never O_TRUNC
 *   ftruncate(fd, AERIE_POSE_SIZE);                                 // only ever to grow it
 *   struct aerie_pose *p = (struct aerie_pose *)mmap(NULL, AERIE_POSE_SIZE,
 *                                  PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
 *   aerie_pose_init(p);
 *   for (;;) {                                  // once per simulator frame
 *       struct aerie_pose v;
 *       aerie_pose_clear(&v);
 *       v.flags = AERIE_POSE_VELOCITY;          // WGS84 position, velocity valid, no rates
 *       v.frame = frame;
 *       v.sim_time_s = t;
 *       v.position[0] = lat_deg; v.position[1] = lon_deg; v.position[2] = alt_m;
 *       v.attitude_deg[0] = heading; v.attitude_deg[1] = pitch; v.attitude_deg[2] = roll;
 *       v.velocity_enu[0] = v_east; v.velocity_enu[1] = v_north; v.velocity_enu[2] = v_up;
 *       aerie_pose_write(p, &v);                // seqlock, fields, checksum
 *   }
 *
 * Conventions (aerie DESIGN.md): heading clockwise from true north, pitch nose up +, roll right
 * wing down +, applied heading-pitch-roll; degrees; altitude in metres above mean sea level
 * (the datasets' vertical datum); local ENU positions in metres from the dataset's origin.
 */
#ifndef AERIE_POSE_H
#define AERIE_POSE_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#define AERIE_POSE_MAGIC 0x53504541u /* the bytes "AEPS" */
#define AERIE_POSE_VERSION 2
#define AERIE_POSE_SIZE 144
#define AERIE_POSE_CRC_START 16 /* the checksum covers bytes 16..136 */
#define AERIE_POSE_CRC_END 136
#define AERIE_POSE_DEFAULT_NAME "aerie-pose"

/* flags */
#define AERIE_POSE_LOCAL_ENU (1u << 0) /* position is x, y, z metres (else lat, lon, alt) */
#define AERIE_POSE_VELOCITY (1u << 1)  /* velocity_enu is valid */
#define AERIE_POSE_RATES (1u << 2)     /* rates_deg_s is valid */

/* aerie_pose_read results */
#define AERIE_POSE_OK 1          /* *out holds a consistent, checksummed pose */
#define AERIE_POSE_BUSY 0        /* never written, or the writer was busy: try again */
#define AERIE_POSE_BAD_HEADER -1 /* wrong magic, version or size */
#define AERIE_POSE_BAD_CRC -2    /* stable record whose checksum does not match */

struct aerie_pose {
    uint32_t magic;          /*   0: AERIE_POSE_MAGIC */
    uint16_t version;        /*   4: AERIE_POSE_VERSION */
    uint16_t size;           /*   6: AERIE_POSE_SIZE */
    uint64_t seq;            /*   8: seqlock: odd = writing, even = stable, 0 = never written */
    uint32_t flags;          /*  16: AERIE_POSE_* flags */
    uint32_t reserved;       /*  20: 0 */
    uint64_t frame;          /*  24: simulator frame number */
    double sim_time_s;       /*  32: simulation time, s */
    double position[3];      /*  40: lat deg, lon deg, alt m  |  x, y, z m (local ENU) */
    double attitude_deg[3];  /*  64: heading, pitch, roll, deg */
    double velocity_enu[3];  /*  88: east, north, up, m/s */
    double rates_deg_s[3];   /* 112: heading, pitch, roll rates, deg/s */
    uint32_t crc;            /* 136: CRC-32 (IEEE 802.3, as zlib) of bytes 16..136 */
    uint32_t reserved2;      /* 140: 0 */
};                           /* 144 bytes */

#if defined(__cplusplus) && __cplusplus >= 201103L
#define AERIE_POSE_STATIC_ASSERT(c, m) static_assert(c, m)
#elif defined(__STDC_VERSION__) && __STDC_VERSION__ >= 201112L
#define AERIE_POSE_STATIC_ASSERT(c, m) _Static_assert(c, m)
#endif
#ifdef AERIE_POSE_STATIC_ASSERT
AERIE_POSE_STATIC_ASSERT(sizeof(struct aerie_pose) == AERIE_POSE_SIZE, "aerie_pose size");
AERIE_POSE_STATIC_ASSERT(offsetof(struct aerie_pose, seq) == 8, "seq offset");
AERIE_POSE_STATIC_ASSERT(offsetof(struct aerie_pose, flags) == 16, "flags offset");
AERIE_POSE_STATIC_ASSERT(offsetof(struct aerie_pose, frame) == 24, "frame offset");
AERIE_POSE_STATIC_ASSERT(offsetof(struct aerie_pose, position) == 40, "position offset");
AERIE_POSE_STATIC_ASSERT(offsetof(struct aerie_pose, attitude_deg) == 64, "attitude offset");
AERIE_POSE_STATIC_ASSERT(offsetof(struct aerie_pose, velocity_enu) == 88, "velocity offset");
AERIE_POSE_STATIC_ASSERT(offsetof(struct aerie_pose, rates_deg_s) == 112, "rates offset");
AERIE_POSE_STATIC_ASSERT(offsetof(struct aerie_pose, crc) == 136, "crc offset");
#undef AERIE_POSE_STATIC_ASSERT
#endif

/* The record as 18 aligned 64-bit words: every shared access is one relaxed __atomic load or
 * store of a word, so a concurrent writer and reader never race on a plain (or volatile)
 * struct copy. Word 2 holds flags and reserved, word 17 crc and reserved2. */
#define AERIE_POSE_WORDS (AERIE_POSE_SIZE / 8)

static inline uint64_t *aerie_pose_word_(struct aerie_pose *p, int i)
{
    return (uint64_t *)(void *)((unsigned char *)p + 8 * i);
}

static inline const uint64_t *aerie_pose_cword_(const struct aerie_pose *p, int i)
{
    return (const uint64_t *)(const void *)((const unsigned char *)p + 8 * i);
}

/* CRC-32 (reflected polynomial 0xEDB88320, initial and final xor 0xFFFFFFFF), four bits a
 * step. aerie_pose_crc32("123456789", 9) == 0xCBF43926. */
static inline uint32_t aerie_pose_crc32(const void *data, size_t len)
{
    static const uint32_t t[16] = {
        0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu, 0x76DC4190u, 0x6B6B51F4u,
        0x4DB26158u, 0x5005713Cu, 0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu,
        0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu,
    };
    const unsigned char *b = (const unsigned char *)data;
    uint32_t c = 0xFFFFFFFFu;
    size_t i;
    for (i = 0; i < len; i++) {
        c ^= b[i];
        c = (c >> 4) ^ t[c & 15u];
        c = (c >> 4) ^ t[c & 15u];
    }
    return c ^ 0xFFFFFFFFu;
}

/* The checksum of a (private) copy of the record: bytes 16..136. */
static inline uint32_t aerie_pose_checksum(const struct aerie_pose *v)
{
    return aerie_pose_crc32((const unsigned char *)v + AERIE_POSE_CRC_START,
                            AERIE_POSE_CRC_END - AERIE_POSE_CRC_START);
}

/* Zeroes a private record before filling it for aerie_pose_write. */
static inline void aerie_pose_clear(struct aerie_pose *v)
{
    memset(v, 0, sizeof *v);
}

/* Writes the header; keeps a running sequence (rounded up to even) so readers see new writes.
 * Call once after mapping the file (and again after the file was regrown). */
static inline void aerie_pose_init(struct aerie_pose *p)
{
    uint32_t magic = __atomic_load_n(&p->magic, __ATOMIC_RELAXED);
    uint16_t version = __atomic_load_n(&p->version, __ATOMIC_RELAXED);
    uint16_t size = __atomic_load_n(&p->size, __ATOMIC_RELAXED);
    uint64_t s = __atomic_load_n(&p->seq, __ATOMIC_RELAXED);
    if (magic != AERIE_POSE_MAGIC || version != AERIE_POSE_VERSION || size != AERIE_POSE_SIZE)
        s = 0;
    __atomic_store_n(&p->seq, (s + 1) & ~(uint64_t)1, __ATOMIC_RELAXED);
    __atomic_store_n(&p->version, (uint16_t)AERIE_POSE_VERSION, __ATOMIC_RELAXED);
    __atomic_store_n(&p->size, (uint16_t)AERIE_POSE_SIZE, __ATOMIC_RELAXED);
    __atomic_store_n(&p->magic, AERIE_POSE_MAGIC, __ATOMIC_RELEASE);
}

/* Publishes the pose in the private record *v (flags, frame, sim_time_s, position,
 * attitude_deg, velocity_enu, rates_deg_s; its header, seq and crc are ignored) into the
 * shared record *p with its checksum. Wait-free. */
static inline void aerie_pose_write(struct aerie_pose *p, const struct aerie_pose *v)
{
    struct aerie_pose c;
    uint64_t w[AERIE_POSE_WORDS];
    uint64_t s;
    int i;
    memcpy(&c, v, sizeof c);
    c.reserved = 0;
    c.reserved2 = 0;
    c.crc = aerie_pose_checksum(&c);
    memcpy(w, &c, sizeof w);
    s = __atomic_load_n(&p->seq, __ATOMIC_RELAXED);
    __atomic_store_n(&p->seq, s + 1, __ATOMIC_RELAXED); /* odd: writing */
    __atomic_thread_fence(__ATOMIC_RELEASE);
    for (i = 2; i < AERIE_POSE_WORDS; i++)
        __atomic_store_n(aerie_pose_word_(p, i), w[i], __ATOMIC_RELAXED);
    __atomic_store_n(&p->seq, s + 2, __ATOMIC_RELEASE); /* even: published */
}

/* Checks a private copy of the record: header, and checksum when seq is even and not 0. */
static inline int aerie_pose_check(const struct aerie_pose *copy)
{
    if (copy->magic != AERIE_POSE_MAGIC || copy->version != AERIE_POSE_VERSION ||
        copy->size != AERIE_POSE_SIZE)
        return AERIE_POSE_BAD_HEADER;
    if (copy->seq == 0 || (copy->seq & 1))
        return AERIE_POSE_BUSY;
    if (copy->crc != aerie_pose_checksum(copy))
        return AERIE_POSE_BAD_CRC;
    return AERIE_POSE_OK;
}

/* Reader side (for tools): copies a consistent pose into *out (a private record). Returns
 * AERIE_POSE_OK, AERIE_POSE_BUSY (never written, or busy for `max_tries` attempts),
 * AERIE_POSE_BAD_HEADER or AERIE_POSE_BAD_CRC. Never blocks. Maps the file: a reader that must
 * survive a writer shrinking the file should pread() it instead (as aerie does) and check the
 * copy with aerie_pose_check. */
static inline int aerie_pose_read(const struct aerie_pose *p, struct aerie_pose *out, int max_tries)
{
    uint64_t w[AERIE_POSE_WORDS];
    int t, i;
    for (t = 0; t < max_tries; t++) {
        uint64_t s1 = __atomic_load_n(&p->seq, __ATOMIC_ACQUIRE);
        if (s1 == 0)
            return AERIE_POSE_BUSY;
        if (s1 & 1)
            continue;
        for (i = 0; i < AERIE_POSE_WORDS; i++)
            w[i] = __atomic_load_n(aerie_pose_cword_(p, i), __ATOMIC_RELAXED);
        __atomic_thread_fence(__ATOMIC_ACQUIRE);
        if (__atomic_load_n(&p->seq, __ATOMIC_RELAXED) != s1)
            continue;
        memcpy(out, w, sizeof w);
        out->seq = s1;
        return aerie_pose_check(out);
    }
    return AERIE_POSE_BUSY;
}

#endif /* AERIE_POSE_H */
