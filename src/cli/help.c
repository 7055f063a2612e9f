/* One help style for every command: `-h` or `--help` anywhere among a command's arguments prints its usage
 * (every flag it accepts, one line each) on stdout and exits 0 (docs/cli.md §1). */
#include <string.h>

#include "dartspp/cli.h"

int cli_help_asked(int argc, char **argv)
{
    for (int i = 0; i < argc; i++)
        if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) return 1;
    return 0;
}
