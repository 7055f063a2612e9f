/* dartspp command line: `dartspp render ...`, `dartspp compare ...`, `dartspp patch-mean ...`,
 * `dartspp merge ...`, `dartspp table ...`. Each returns the process exit
 * status: 0 success, 2 bad input (message on stderr), 1 other failures. */
#ifndef DARTSPP_CLI_H
#define DARTSPP_CLI_H

int cli_render(int argc, char **argv);
int cli_compare(int argc, char **argv);
int cli_patch_mean(int argc, char **argv);
int cli_merge(int argc, char **argv);
int cli_table(int argc, char **argv);

#endif
