/*
 * A simulator-side writer built from aerie_pose.h, compiled by the test suite as C99 (gcc) and
 * as C++11 and C++17 (g++) with -Wall -Wextra -pedantic -Werror. It writes poses 1..N (every
 * field a function of k, so the Rust reader can tell a torn or corrupted read) about every
 * 50 us, then reads the last one back with aerie_pose_read.
 *
 *   shm_writer <file> <N>
 * Exit status: 0 done, 1 I/O failure, 2 bad arguments, 3 read-back or checksum self-test failed.
 */
#define _POSIX_C_SOURCE 200809L
#include <fcntl.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>

#include "aerie_pose.h"

static void pose_k(struct aerie_pose *v, uint64_t k)
{
    double x = (double)k;
    aerie_pose_clear(v);
    v->flags = AERIE_POSE_LOCAL_ENU | AERIE_POSE_VELOCITY | (k % 2 ? 0u : AERIE_POSE_RATES);
    v->frame = k;
    v->sim_time_s = 0.001 * x;
    v->position[0] = x;
    v->position[1] = -2.0 * x;
    v->position[2] = 1000.0 + 0.5 * x;
    v->attitude_deg[0] = (double)(k % 360);
    v->attitude_deg[1] = (double)(k % 170) - 85.0;
    v->attitude_deg[2] = -x / 1e4;
    /* Speeds and rates in physical ranges (aerie drops implausible ones). */
    v->velocity_enu[0] = (double)(k % 200) + 1.0;
    v->velocity_enu[1] = (double)(k % 200) + 2.0;
    v->velocity_enu[2] = (double)(k % 200) + 3.0;
    if (k % 2 == 0) {
        v->rates_deg_s[0] = (double)(k % 30);
        v->rates_deg_s[1] = (double)(k % 30);
        v->rates_deg_s[2] = (double)(k % 30);
    }
}

int main(int argc, char **argv)
{
    struct aerie_pose v, back;
    struct aerie_pose *p;
    struct timespec pause;
    uint64_t k, n;
    int fd;
    if (argc != 3)
        return 2;
    n = strtoull(argv[2], NULL, 10);
    if (aerie_pose_crc32("123456789", 9) != 0xCBF43926u)
        return 3;
    fd = open(argv[1], O_RDWR | O_CREAT, 0644);
    if (fd < 0 || ftruncate(fd, AERIE_POSE_SIZE) != 0)
        return 1;
    p = (struct aerie_pose *)mmap(NULL, AERIE_POSE_SIZE, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    if (p == MAP_FAILED)
        return 1;
    aerie_pose_init(p);
    pause.tv_sec = 0;
    pause.tv_nsec = 50000;
    for (k = 1; k <= n; k++) {
        pose_k(&v, k);
        aerie_pose_write(p, &v);
        nanosleep(&pause, NULL);
    }
    if (aerie_pose_read(p, &back, 10) != AERIE_POSE_OK || back.frame != n)
        return 3;
    pose_k(&v, n);
    if (back.position[2] != v.position[2] || back.crc != aerie_pose_checksum(&back))
        return 3;
    /* A corrupted shared record is refused by the reader function too. */
    p->position[0] += 1.0;
    if (aerie_pose_read(p, &back, 10) != AERIE_POSE_BAD_CRC)
        return 3;
    aerie_pose_write(p, &v);
    munmap(p, AERIE_POSE_SIZE);
    close(fd);
    return 0;
}
