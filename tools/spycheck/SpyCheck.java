// Listens to every channel of an LCM bus for SECONDS, or until its standard
// input ends, and decodes each message the way lcm-spy does: by its
// fingerprint, with the LCM types found on the CLASSPATH
// (lcm.spy.LCMTypeDatabase). Prints, per channel, the messages heard and
// their type. Exits 1 if a message could not be decoded, or if one of the
// expected channels was never heard; 2 on bad arguments.
//   java -cp afford-lcmtypes.jar:afford-spycheck.jar:lcm.jar SpyCheck URL SECONDS [CHANNEL,...]
import java.io.IOException;
import java.util.Map;
import java.util.TreeMap;

import lcm.lcm.LCM;
import lcm.lcm.LCMDataInputStream;
import lcm.lcm.LCMSubscriber;
import lcm.spy.LCMTypeDatabase;

public class SpyCheck implements LCMSubscriber {
  static class Stat {
    long heard = 0, undecodable = 0;
    String type = "?";
  }

  private final LCMTypeDatabase types = new LCMTypeDatabase();
  private final Map<String, Stat> stats = new TreeMap<>();

  public synchronized void messageReceived(LCM lcm, String channel, LCMDataInputStream ins) {
    if (channel.equals("LCM_SELF_TEST")) return;  // Java LCM's own start-up probe, not a message of ours
    Stat s = stats.computeIfAbsent(channel, k -> new Stat());
    s.heard++;
    try {
      byte[] data = new byte[ins.available()];
      ins.readFully(data);
      long fingerprint = 0;
      for (int i = 0; i < 8 && i < data.length; i++) fingerprint = (fingerprint << 8) | (data[i] & 0xff);
      Class<?> cls = types.getClassByFingerprint(fingerprint);
      if (cls == null) {
        s.undecodable++;
        return;
      }
      cls.getConstructor(byte[].class).newInstance((Object) data);
      s.type = cls.getName();
    } catch (Exception e) {
      s.undecodable++;
    }
  }

  public static void main(String[] args) throws IOException, InterruptedException {
    if (args.length < 2) {
      System.err.println("usage: SpyCheck URL SECONDS [CHANNEL,...]");
      System.exit(2);
    }
    SpyCheck check = new SpyCheck();
    LCM lcm = new LCM(args[0]);
    lcm.subscribe(".*", check);
    System.out.println("listening on " + args[0]);  // the test starts the run on this line
    System.out.flush();
    // Until SECONDS have passed or its standard input ends (closed by a caller who knows the bus has said all).
    Thread input = new Thread(() -> {
      try {
        while (System.in.read() >= 0) {}
      } catch (IOException e) {
      }
    });
    input.setDaemon(true);
    input.start();
    input.join((long) (Double.parseDouble(args[1]) * 1000));
    lcm.unsubscribe(".*", check);
    int status = 0;
    synchronized (check) {
      if (check.stats.isEmpty()) {
        System.out.println("nothing heard on " + args[0]);
        status = 1;
      }
      for (Map.Entry<String, Stat> e : check.stats.entrySet()) {
        Stat s = e.getValue();
        System.out.printf("%-20s %8d heard  %6d undecodable  %s%n", e.getKey(), s.heard, s.undecodable, s.type);
        if (s.undecodable > 0) status = 1;
      }
      if (args.length > 2)
        for (String ch : args[2].split(","))
          if (!check.stats.containsKey(ch)) {
            System.out.println("never heard: " + ch);
            status = 1;
          }
    }
    lcm.close();
    System.exit(status);
  }
}
