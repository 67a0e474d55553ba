/* Plugin files: ELF checks run before dlopen (elf_check.c). Internal to libtunetrace. */
#ifndef TT_PLUGIN_ELF_CHECK_H
#define TT_PLUGIN_ELF_CHECK_H

#include <tunetrace/common.h>

/* Checks that `path` is a regular ELF shared object of this process's class and byte order
 * whose program headers and segments all lie inside the file, so that dlopen cannot fault
 * on a truncated file. TT_OK, or TT_ERR_IO / TT_ERR_ABI with a message naming the file. */
tt_status tt__elf_check_plugin(const char *path);

#endif /* TT_PLUGIN_ELF_CHECK_H */
