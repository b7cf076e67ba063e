/* What the C test hosts (fmi2_host.c, fmi3_host.c) drive FMUs with, alike so that their rows compare
 * line by line: the inputs u_j(t) = A (sin(2 pi t / P + j) + S q(t)), q the square wave that is 1 on
 * the first half of each period P, and splitmix64 random numbers (the same steps for the same seed on
 * every machine). */
#ifndef HOST_SIGNALS_H
#define HOST_SIGNALS_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#ifndef M_PI /* -std=c99 hides it in some C libraries */
#define M_PI 3.14159265358979323846
#endif

static double host_input(double t, size_t j, double amplitude, double period, double square)
{
    double phase = fmod(t, period);
    return amplitude * (sin(2.0 * M_PI * t / period + (double)j) + (phase < 0.5 * period ? square : 0.0));
}

static uint64_t rng_state;
static double uniform01(void)
{
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

#endif
