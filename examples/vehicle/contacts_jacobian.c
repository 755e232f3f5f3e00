/* The contacts' Jacobian as exudyn takes it: (row, column, value) triplets, repeated
 * entries summed (contacts._triplets and contacts._tyre_triplets in C). */
#include "contacts.h"

#define P(name) (c->parameter[P_##name])
#define ARRAY(name) (c->array[A_##name])

void triplets_put(Triplets *t, int row, int column, double value)
{
    if (t->count < t->capacity) {
        double *entry = t->out + 3 * t->count;
        entry[0] = row;
        entry[1] = column;
        entry[2] = value;
    }
    t->count++;
}

/* Every spring's block, members a, b: w_a G_a^T (factor K + factor_t C) w_b H_b. */
static void spring_triplets(const Contacts *c, double factor, double factor_t, Triplets *t)
{
    for (int s = 0; s < c->springs; s++) {
        const Spring *spring = &c->spring[s];
        double block[2][2];
        for (int j = 0; j < 2; j++)
            for (int k = 0; k < 2; k++)
                block[j][k] = factor * spring->stiffness[j][k] + factor_t * spring->damping[j][k];
        for (int a = 0; a < spring->members; a++)
            for (int b = 0; b < spring->members; b++)
                for (int i = 0; i < 3; i++)
                    for (int l = 0; l < 3; l++) {
                        double value = 0.0;
                        for (int j = 0; j < 2; j++)
                            for (int k = 0; k < 2; k++)
                                value += spring->weight[a] * spring->force_g[a][j][i]
                                         * block[j][k]
                                         * (spring->weight[b] * spring->motion_g[b][k][l]);
                        triplets_put(t, 3 * spring->body[a] + i, 3 * spring->body[b] + l, value);
                    }
    }
}

/* The tyres' factor K + factor_t C of each wheel in contact, from the blend's gradient D
 * (a row per link beneath) and weights p: K = F' (p.D)^T (p.D) + F/b D^T (diag(p) - p p^T)
 * D (b TYRE_BLEND), C = F_rate (p.D)^T (p.D), on the coordinates D touches. */
static void tyre_triplets(Contacts *c, double factor, double factor_t, Triplets *t)
{
    const double *force = ARRAY(TYRE_FORCE), *slope = ARRAY(SLOPES);
    const double *rate_slope = ARRAY(RATE_SLOPES);
    double blend = P(TYRE_BLEND);
    for (int i = 0; i < c->pairs; i++) {
        int w = c->pair_wheel[i];
        if (!(force[w] > 0.0)) continue;
        const double *gradient = c->pair_gradient + 12 * i;
        const int *coordinate = c->pair_coordinate + 12 * i;
        double scale = factor * force[w] / blend * c->pair_weight[i];
        for (int a = 0; a < 12; a++)
            for (int b = 0; b < 12; b++)
                triplets_put(t, coordinate[a], coordinate[b], scale * gradient[a] * gradient[b]);
    }
    /* (factor (F' - F/b) + factor_t F_rate) (p.D)^T (p.D): p.D's entries, the arm's summed
     * over the wheel's links, in the numpy kernel's order (every wheel's arm entries, then
     * every pair's links') */
    int entries = 0;
    for (int w = 0; w < c->wheels; w++) {
        if (!(force[w] > 0.0)) continue;
        double by_wheel[3] = {0.0, 0.0, 0.0};
        for (int i = 0; i < c->pairs; i++)
            if (c->pair_wheel[i] == w)
                for (int k = 0; k < 3; k++)
                    by_wheel[k] += c->pair_weight[i] * c->pair_gradient[12 * i + k];
        for (int k = 0; k < 3; k++) {
            c->entry_wheel[entries] = w;
            c->entry_coordinate[entries] = 3 * (1 + w) + k;
            c->entry_value[entries++] = by_wheel[k];
        }
    }
    for (int i = 0; i < c->pairs; i++) {
        int w = c->pair_wheel[i];
        if (!(force[w] > 0.0)) continue;
        for (int k = 3; k < 12; k++) {
            c->entry_wheel[entries] = w;
            c->entry_coordinate[entries] = c->pair_coordinate[12 * i + k];
            c->entry_value[entries++] = c->pair_weight[i] * c->pair_gradient[12 * i + k];
        }
    }
    for (int a = 0; a < entries; a++)
        for (int b = 0; b < entries; b++) {
            int w = c->entry_wheel[a];
            if (c->entry_wheel[b] != w) continue;
            triplets_put(t, c->entry_coordinate[a], c->entry_coordinate[b],
                (factor * (slope[w] - force[w] / blend) + factor_t * rate_slope[w])
                * c->entry_value[a] * c->entry_value[b]);
        }
}

/* Writes the triplets (rows of row, column, value) into out while they fit `capacity`;
 * returns how many there are (call again with a larger out where that is more). */
CONTACTS_EXPORT long contacts_jacobian(Contacts *c, double factor, double factor_t,
                                       double *out, long capacity)
{
    Triplets t = {out, 0, capacity};
    spring_triplets(c, factor, factor_t, &t);
    tyre_triplets(c, factor, factor_t, &t);
    return t.count;
}
