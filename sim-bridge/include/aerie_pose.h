/*
 * aerie_pose.h — shared-memory pose input for the aerie image generator.
 *
 * A simulator on the same host writes its ownship pose into a 136-byte file, by default
 * /dev/shm/aerie-pose (aerie: `aerie listen --protocol shm --shm-name aerie-pose`). One writer; any number of
 * readers. A seqlock guards the fields: `seq` is odd while a write is in progress and even
 * when the fields are stable (0 = never written). Readers never block the writer; they retry
 * a read that overlapped a write.
 *
 * Host byte order (little-endian on x86-64 and AArch64). Needs GCC or Clang (__atomic builtins).
 *
 *   int fd = open("/dev/shm/aerie-pose", O_RDWR | O_CREAT, 0644);
 *   ftruncate(fd, AERIE_POSE_SIZE);
 *   struct aerie_pose *p = mmap(NULL, AERIE_POSE_SIZE, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
 *   aerie_pose_init(p);
 *   for (;;) {                                  // once per simulator frame
 *       aerie_pose_begin(p);
 *       p->flags = AERIE_POSE_VELOCITY;         // WGS84 position, velocity valid, no rates
 *       p->frame = frame;
 *       p->sim_time_s = t;
 *       p->position[0] = lat_deg; p->position[1] = lon_deg; p->position[2] = alt_m;
 *       p->attitude_deg[0] = heading; p->attitude_deg[1] = pitch; p->attitude_deg[2] = roll;
 *       p->velocity_enu[0] = v_east; p->velocity_enu[1] = v_north; p->velocity_enu[2] = v_up;
 *       aerie_pose_end(p);
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

#define AERIE_POSE_MAGIC 0x53504541u /* the bytes "AEPS" */
#define AERIE_POSE_VERSION 1
#define AERIE_POSE_SIZE 136
#define AERIE_POSE_DEFAULT_NAME "aerie-pose"

/* flags */
#define AERIE_POSE_LOCAL_ENU (1u << 0) /* position is x, y, z metres (else lat, lon, alt) */
#define AERIE_POSE_VELOCITY (1u << 1)  /* velocity_enu is valid */
#define AERIE_POSE_RATES (1u << 2)     /* rates_deg_s is valid */

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
};                           /* 136 bytes */

#if defined(__STDC_VERSION__) && __STDC_VERSION__ >= 201112L
_Static_assert(sizeof(struct aerie_pose) == AERIE_POSE_SIZE, "aerie_pose size");
_Static_assert(offsetof(struct aerie_pose, seq) == 8, "seq offset");
_Static_assert(offsetof(struct aerie_pose, flags) == 16, "flags offset");
_Static_assert(offsetof(struct aerie_pose, frame) == 24, "frame offset");
_Static_assert(offsetof(struct aerie_pose, position) == 40, "position offset");
_Static_assert(offsetof(struct aerie_pose, attitude_deg) == 64, "attitude offset");
_Static_assert(offsetof(struct aerie_pose, velocity_enu) == 88, "velocity offset");
_Static_assert(offsetof(struct aerie_pose, rates_deg_s) == 112, "rates offset");
#endif

/* Writes the header; keeps a running sequence (rounded up to even) so readers see new writes. */
static inline void aerie_pose_init(struct aerie_pose *p)
{
    uint64_t s = __atomic_load_n(&p->seq, __ATOMIC_RELAXED);
    if (p->magic != AERIE_POSE_MAGIC || p->version != AERIE_POSE_VERSION || p->size != AERIE_POSE_SIZE)
        s = 0;
    __atomic_store_n(&p->seq, (s + 1) & ~(uint64_t)1, __ATOMIC_RELAXED);
    p->reserved = 0;
    p->version = AERIE_POSE_VERSION;
    p->size = AERIE_POSE_SIZE;
    __atomic_store_n(&p->magic, AERIE_POSE_MAGIC, __ATOMIC_RELEASE);
}

/* Starts a write: seq becomes odd. */
static inline void aerie_pose_begin(struct aerie_pose *p)
{
    uint64_t s = __atomic_load_n(&p->seq, __ATOMIC_RELAXED);
    __atomic_store_n(&p->seq, s + 1, __ATOMIC_RELAXED);
    __atomic_thread_fence(__ATOMIC_RELEASE);
}

/* Ends a write: seq becomes even; the fields are published. */
static inline void aerie_pose_end(struct aerie_pose *p)
{
    uint64_t s = __atomic_load_n(&p->seq, __ATOMIC_RELAXED);
    __atomic_store_n(&p->seq, s + 1, __ATOMIC_RELEASE);
}

/* Reader side (for tools): copies a consistent pose into *out. Returns 1 on success, 0 if the
 * writer was busy for `max_tries` attempts or has never written. Never blocks. */
static inline int aerie_pose_read(const struct aerie_pose *p, struct aerie_pose *out, int max_tries)
{
    for (int i = 0; i < max_tries; i++) {
        uint64_t s1 = __atomic_load_n(&p->seq, __ATOMIC_ACQUIRE);
        if (s1 == 0)
            return 0;
        if (s1 & 1)
            continue;
        *out = *(const volatile struct aerie_pose *)p;
        __atomic_thread_fence(__ATOMIC_ACQUIRE);
        if (__atomic_load_n(&p->seq, __ATOMIC_RELAXED) == s1) {
            out->seq = s1;
            return 1;
        }
    }
    return 0;
}

#endif /* AERIE_POSE_H */
