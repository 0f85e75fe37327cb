// Reads an LCM log with Java LCM's own log reader and decodes every event
// the way lcm-spy does (fingerprint -> class from the type jars on the
// class path, then the class's DataInput constructor). Prints one line per
// channel: "CHANNEL decoded N undecodable M".
import java.io.DataInput;
import java.io.EOFException;
import java.util.Map;
import java.util.TreeMap;

import lcm.lcm.LCMDataInputStream;
import lcm.logging.Log;
import lcm.spy.LCMTypeDatabase;

public class LogDecodeCheck {
  public static void main(String[] args) throws Exception {
    LCMTypeDatabase types = new LCMTypeDatabase();
    Map<String, int[]> counts = new TreeMap<>();
    Log log = new Log(args[0], "r");
    while (true) {
      Log.Event event;
      try {
        event = log.readNext();
      } catch (EOFException end) {
        break;
      }
      int[] c = counts.computeIfAbsent(event.channel, k -> new int[2]);
      c[decodes(types, event.data) ? 0 : 1]++;
    }
    for (Map.Entry<String, int[]> e : counts.entrySet())
      System.out.println(e.getKey() + " decoded " + e.getValue()[0] + " undecodable " + e.getValue()[1]);
  }

  static boolean decodes(LCMTypeDatabase types, byte[] data) {
    try {
      LCMDataInputStream in = new LCMDataInputStream(data);
      Class<?> cls = types.getClassByFingerprint(in.readLong());
      if (cls == null) return false;
      in.reset();
      cls.getConstructor(DataInput.class).newInstance(in);
      return true;
    } catch (Exception e) {
      return false;
    }
  }
}
