/* The key table (src/scene/keys.c) for the embedding API, row by row, with the columns of `dartspp keys`. */
#include <stdio.h>

#include "dartspp/api.h"
#include "dartspp/scene.h"

int dp_key_count(void)
{
    int n;
    scene_keys(&n);
    return n;
}

void dp_key_get(int i, dp_key_row *row)
{
    int n;
    const scene_key *k = &scene_keys(&n)[i];
    *row = (dp_key_row){.section = scene_key_section_name(k->section), .name = k->name,
                        .type = scene_key_type_name(k->type), .meaning = k->meaning, .changes_image = k->changes_image};
    scene_key_default_text(k, row->def, sizeof row->def);
    scene_key_range_text(k, row->range, sizeof row->range);
    scene_key_readers_text(k, row->readers, sizeof row->readers);
}
