/* The contract between the native reference player's model part (table_part.c, written once) and
 * the model.c that shapefmu.fmi.native.reference generates for one build: the variables of the
 * pythonfmu ReferencePlayer and its signal table, parsed at build time by runtime/reference_player.py
 * (the distinct times, the values arriving at and leaving each, the running integral). */
#ifndef TABLE_MODEL_H
#define TABLE_MODEL_H

#include "model.h"

typedef struct {
    const char *guid;
    /* the table parameter's start value, the JSON text of the build, in pieces of at most
     * 4000 bytes (shapefmu.fmi.native.reference.TEXT_PIECE): a string literal each, which every C compiler takes, and which gcc reads
     * at megabytes a second (a list of byte values took it minutes for a 15 MB table) */
    const char *const *table_text;
    size_t n_text_pieces;
    size_t n_times;
    const double *times, *left, *right, *integral;  /* n_times each */
    int hold;                     /* 1: zero-order hold, 0: linear */
    double before, tolerance;     /* the value before the first time; times within tolerance snap */
} TableModel;

extern const TableModel table_model;

#endif
