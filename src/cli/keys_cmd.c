/* `dartspp keys [--markdown]`: the key table (src/scene/keys.c) as text, or as the Markdown of docs/keys.md. */
#include <stdio.h>
#include <string.h>

#include "dartspp/cli.h"
#include "dartspp/scene.h"

typedef struct {
    char type[32], def[64], range[128], readers[128];
} key_columns;

static void columns_of(const scene_key *k, key_columns *c)
{
    snprintf(c->type, sizeof c->type, "%s", scene_key_type_name(k->type));
    scene_key_default_text(k, c->def, sizeof c->def);
    scene_key_range_text(k, c->range, sizeof c->range);
    scene_key_readers_text(k, c->readers, sizeof c->readers);
}

static void print_text(const scene_key *keys, int n)
{
    for (int i = 0; i < n; i++) {
        key_columns c;
        columns_of(&keys[i], &c);
        printf("%s.%s  %s  default %s  range %s  read by %s%s\n    %s\n", scene_key_section_name(keys[i].section),
               keys[i].name, c.type, c.def, c.range, c.readers, keys[i].changes_image ? "  changes the image" : "",
               keys[i].meaning);
    }
}

static void print_markdown(const scene_key *keys, int n)
{
    for (int s = KEY_SECTION_INTEGRATOR; s <= KEY_SECTION_RENDERER; s++) {
        printf("%s### `%s`\n\n| key | type | default | range | read by | changes the image | meaning |\n"
               "|---|---|---|---|---|---|---|\n", s ? "\n" : "", scene_key_section_name(s));
        for (int i = 0; i < n; i++) {
            if ((int)keys[i].section != s) continue;
            key_columns c;
            columns_of(&keys[i], &c);
            printf("| `%s` | %s | %s | %s | %s | %s | %s |\n", keys[i].name, c.type, c.def, c.range, c.readers,
                   keys[i].changes_image ? "yes" : "no", keys[i].meaning);
        }
    }
}

static void usage(FILE *f)
{
    fprintf(f, "usage: dartspp keys [--markdown]   (every integrator and renderer key: type, default, range, meaning)\n"
               "  --markdown  as the tables of docs/keys.md\n"
               "  -h, --help  this text\n");
}

int cli_keys(int argc, char **argv)
{
    if (cli_help_asked(argc, argv)) {
        usage(stdout);
        return 0;
    }
    int markdown = argc == 1 && !strcmp(argv[0], "--markdown");
    if (argc > 1 || (argc == 1 && !markdown)) {
        usage(stderr);
        return 2;
    }
    int n;
    const scene_key *keys = scene_keys(&n);
    if (markdown) print_markdown(keys, n);
    else print_text(keys, n);
    return 0;
}
