/* Plugin files: the ELF header and program headers checked against the file size before
 * dlopen. The dynamic loader mmap()s every PT_LOAD segment as the program headers describe
 * it; a segment that runs past the end of a truncated file is mapped all the same, and the
 * first touch of a page beyond EOF raises SIGBUS inside dlopen, where no caller can recover.
 * Reading the headers ourselves turns that into an error that names the file. The section
 * headers are checked too: a file cut past its last segment would load and run. */
#include "plugin/elf_check.h"
#include "util/files.h"

#include <elf.h>
#include <errno.h>
#include <fcntl.h>
#include <link.h>
#include <stdint.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The ELF class and byte order this process runs with: a plugin must match them. */
#if __SIZEOF_POINTER__ == 8
#  define TT__ELF_CLASS ELFCLASS64
#else
#  define TT__ELF_CLASS ELFCLASS32
#endif
#if __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
#  define TT__ELF_DATA ELFDATA2LSB
#else
#  define TT__ELF_DATA ELFDATA2MSB
#endif

/* More program headers than any linker writes; also keeps PN_XNUM (extended count) out. */
#define TT__ELF_MAX_PHDRS 4096

/* Reads exactly `n` bytes at `off`; 0 on success. */
static int tt__pread_all(int fd, void *buf, size_t n, off_t off) {
  unsigned char *p = buf;
  while (n > 0) {
    ssize_t got = pread(fd, p, n, off);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return -1;
    p += got;
    n -= (size_t)got;
    off += got;
  }
  return 0;
}

/* Name of a segment type for messages. */
static const char *tt__ptype(uint32_t t) {
  switch (t) {
  case PT_LOAD: return "PT_LOAD";
  case PT_DYNAMIC: return "PT_DYNAMIC";
  case PT_INTERP: return "PT_INTERP";
  case PT_NOTE: return "PT_NOTE";
  case PT_PHDR: return "PT_PHDR";
  case PT_TLS: return "PT_TLS";
  case PT_GNU_EH_FRAME: return "PT_GNU_EH_FRAME";
  case PT_GNU_RELRO: return "PT_GNU_RELRO";
  default: return "segment";
  }
}

tt_status tt__elf_check_plugin(const char *path) {
  /* the one input check (util/files.h): a FIFO named NAME.so must not block the open */
  struct stat sb;
  char why[256];
  int fd = tt__open_regular_fd(path, &sb, why, sizeof why);
  if (fd < 0) return tt_set_error(TT_ERR_IO, "cannot load plugin %s: %s", path, why);
  tt_status st = TT_OK;
  ElfW(Ehdr) eh;
  const uint64_t size = (uint64_t)sb.st_size;
  if (size < EI_NIDENT || tt__pread_all(fd, eh.e_ident, EI_NIDENT, 0) != 0 ||
      memcmp(eh.e_ident, ELFMAG, SELFMAG) != 0) {
    st = tt_set_error(TT_ERR_ABI,
                      "cannot load plugin %s: not an ELF shared object (%llu bytes, "
                      "no ELF magic)",
                      path, (unsigned long long)size);
    goto done;
  }
  if (eh.e_ident[EI_CLASS] != TT__ELF_CLASS || eh.e_ident[EI_DATA] != TT__ELF_DATA) {
    st = tt_set_error(TT_ERR_ABI,
                      "cannot load plugin %s: ELF %s-bit %s-endian, this host is "
                      "%d-bit %s-endian",
                      path, eh.e_ident[EI_CLASS] == ELFCLASS64 ? "64" : "32",
                      eh.e_ident[EI_DATA] == ELFDATA2MSB ? "big" : "little",
                      (int)(8 * sizeof(void *)), TT__ELF_DATA == ELFDATA2MSB ? "big" : "little");
    goto done;
  }
  if (size < sizeof eh || tt__pread_all(fd, &eh, sizeof eh, 0) != 0) {
    st = tt_set_error(TT_ERR_ABI,
                      "cannot load plugin %s: truncated ELF file: %llu bytes, shorter "
                      "than its %zu-byte header",
                      path, (unsigned long long)size, sizeof eh);
    goto done;
  }
  if (eh.e_type != ET_DYN) {
    st = tt_set_error(TT_ERR_ABI,
                      "cannot load plugin %s: ELF type %u is not a shared object "
                      "(ET_DYN)",
                      path, (unsigned)eh.e_type);
    goto done;
  }
  if (eh.e_phentsize != sizeof(ElfW(Phdr)) || eh.e_phnum == 0 || eh.e_phnum > TT__ELF_MAX_PHDRS) {
    st = tt_set_error(TT_ERR_ABI,
                      "cannot load plugin %s: corrupt ELF header (%u program headers "
                      "of %u bytes)",
                      path, (unsigned)eh.e_phnum, (unsigned)eh.e_phentsize);
    goto done;
  }
  const uint64_t ph_end = (uint64_t)eh.e_phoff + (uint64_t)eh.e_phnum * sizeof(ElfW(Phdr));
  if (eh.e_phoff > size || ph_end > size) {
    st = tt_set_error(TT_ERR_ABI,
                      "cannot load plugin %s: truncated ELF file: program headers end "
                      "at byte %llu, the file has %llu bytes",
                      path, (unsigned long long)ph_end, (unsigned long long)size);
    goto done;
  }
  int loads = 0;
  for (unsigned i = 0; i < eh.e_phnum; i++) {
    ElfW(Phdr) ph;
    if (tt__pread_all(fd, &ph, sizeof ph, (off_t)(eh.e_phoff + (uint64_t)i * sizeof ph)) != 0) {
      st =
          tt_set_error(TT_ERR_IO, "cannot load plugin %s: read error in the program headers", path);
      goto done;
    }
    if (ph.p_type == PT_NULL) continue;
    loads += ph.p_type == PT_LOAD;
    /* every byte the loader maps or reads from the file must exist (overflow-safe) */
    if ((uint64_t)ph.p_offset > size || (uint64_t)ph.p_filesz > size - (uint64_t)ph.p_offset) {
      st = tt_set_error(TT_ERR_ABI,
                        "cannot load plugin %s: truncated ELF file: %s %u ends at "
                        "byte %llu, the file has %llu bytes",
                        path, tt__ptype(ph.p_type), i,
                        (unsigned long long)((uint64_t)ph.p_offset + (uint64_t)ph.p_filesz),
                        (unsigned long long)size);
      goto done;
    }
    if (ph.p_type == PT_LOAD && ph.p_filesz > ph.p_memsz) {
      st = tt_set_error(TT_ERR_ABI,
                        "cannot load plugin %s: corrupt ELF file: PT_LOAD %u has "
                        "more file bytes (%llu) than memory bytes (%llu)",
                        path, i, (unsigned long long)ph.p_filesz, (unsigned long long)ph.p_memsz);
      goto done;
    }
  }
  if (loads == 0) {
    st = tt_set_error(TT_ERR_ABI, "cannot load plugin %s: corrupt ELF file: no PT_LOAD segment",
                      path);
    goto done;
  }
  /* The section headers (and what they describe) are not mapped, so a file cut anywhere
   * past its last segment still loaded and ran: a plugin half copied by an interrupted
   * install or download. Linkers write the section header table last, so checking that it
   * and every section with file bytes are inside the file finds a file cut short anywhere. */
  if (eh.e_shoff != 0) {
    uint64_t shnum = eh.e_shnum;
    if (eh.e_shentsize != sizeof(ElfW(Shdr))) {
      st = tt_set_error(TT_ERR_ABI,
                        "cannot load plugin %s: corrupt ELF header (section headers "
                        "of %u bytes)",
                        path, (unsigned)eh.e_shentsize);
      goto done;
    }
    ElfW(Shdr) sh0;
    if (eh.e_shoff > size || sizeof sh0 > size - (uint64_t)eh.e_shoff ||
        tt__pread_all(fd, &sh0, sizeof sh0, (off_t)eh.e_shoff) != 0) {
      st = tt_set_error(TT_ERR_ABI,
                        "cannot load plugin %s: truncated ELF file: the section "
                        "headers start at byte %llu, the file has %llu bytes",
                        path, (unsigned long long)eh.e_shoff, (unsigned long long)size);
      goto done;
    }
    if (shnum == 0) shnum = sh0.sh_size; /* extended numbering (SHN_LORESERVE or more) */
    const uint64_t sh_end = (uint64_t)eh.e_shoff + shnum * sizeof(ElfW(Shdr));
    if (shnum > (size / sizeof(ElfW(Shdr))) || sh_end > size) {
      st = tt_set_error(TT_ERR_ABI,
                        "cannot load plugin %s: truncated ELF file: section headers "
                        "end at byte %llu, the file has %llu bytes",
                        path, (unsigned long long)sh_end, (unsigned long long)size);
      goto done;
    }
    for (uint64_t i = 1; i < shnum; i++) {
      ElfW(Shdr) sh;
      if (tt__pread_all(fd, &sh, sizeof sh, (off_t)(eh.e_shoff + i * sizeof sh)) != 0) {
        st = tt_set_error(TT_ERR_IO, "cannot load plugin %s: read error in the section headers",
                          path);
        goto done;
      }
      if (sh.sh_type == SHT_NOBITS || sh.sh_type == SHT_NULL) continue;
      if ((uint64_t)sh.sh_offset > size || (uint64_t)sh.sh_size > size - (uint64_t)sh.sh_offset) {
        st = tt_set_error(TT_ERR_ABI,
                          "cannot load plugin %s: truncated ELF file: section %llu "
                          "ends at byte %llu, the file has %llu bytes",
                          path, (unsigned long long)i,
                          (unsigned long long)((uint64_t)sh.sh_offset + (uint64_t)sh.sh_size),
                          (unsigned long long)size);
        goto done;
      }
    }
  }
done:
  close(fd);
  return st;
}
